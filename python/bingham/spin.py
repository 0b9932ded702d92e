"""The second-order quaternion Bingham filter of Glover & Kaelbling (2013): :class:`SpinFilter`,
owning a ``bingham_spin_filter`` handle (orientation and spin of an object observed without a
gyroscope, e.g. by a camera)."""

from __future__ import annotations

import ctypes
from typing import Optional, Tuple

import numpy as np

from ._arrays import Array, ArrayLike, _in, _ptr
from .errors import _check
from ._handle import _Handle
from ._library import lib

__all__ = ["SpinFilter"]


def _dist4(m: ArrayLike, z: ArrayLike, names: Tuple[str, str]) -> Tuple[Array, Array]:
    return _in(m, names[0], (4, 4)), _in(z, names[1], (4,))


class SpinFilter(_Handle):
    """The second-order quaternion Bingham filter (Glover & Kaelbling 2013): the orientation
    ``x`` and the spin ``v`` (the rotation per time step), unit quaternions scalar first
    ``(w, x, y, z)``, owning a ``bingham_spin_filter`` handle.

    Model (``q ∘ r`` is the Hamilton product ``q r``, "rotate by r, then by q", as
    :func:`quat_multiply`): ``v[n] = w[n] ∘ u[n] ∘ v[n-1]``, ``x[n] = v[n-1] ∘ x[n-1]``,
    ``y[n] = o[n] ∘ x[n]``, with Bingham noises ``w ~ (m_w, z_w)`` (process, on the spin; mode
    at the identity for zero-mean noise) and ``o ~ (m_o, z_o)`` (observation), and an optional
    known change of spin ``u``. The state is the product of two Bingham marginals,
    :meth:`orientation` and :meth:`spin`; each step is three moment-matched compositions and
    two exact Bayes products.

    ``SpinFilter(m_x, z_x, m_v, z_v)``: the orientation prior Bingham(m_x, z_x) (``z_x`` all
    equal, e.g. zeros: uniform, nothing known) and the spin prior Bingham(m_v, z_v) (mode
    ``(1, 0, 0, 0)``: no spin). A failed call raises :class:`BinghamError` (or
    :class:`ValueError` for a wrong shape) and leaves the filter unchanged. Use one filter per
    thread at a time; :meth:`clone` gives an independent copy (a bank of spin hypotheses is a
    list of filters and a running sum of :meth:`log_likelihood`). The handle is released by
    :meth:`close`, by leaving a ``with`` block, or when the object is garbage collected.
    """

    _free = "bingham_spin_filter_free"
    _what = "spin filter"

    def __init__(self, m_x: ArrayLike, z_x: ArrayLike, m_v: ArrayLike, z_v: ArrayLike) -> None:
        m_x, z_x = _dist4(m_x, z_x, ("m_x", "z_x"))
        m_v, z_v = _dist4(m_v, z_v, ("m_v", "z_v"))
        handle = ctypes.c_void_p()
        _check(lib().bingham_spin_filter_new(_ptr(m_x), _ptr(z_x), _ptr(m_v), _ptr(z_v), ctypes.byref(handle)))
        self._handle: Optional[ctypes.c_void_p] = handle

    @classmethod
    def _adopt(cls, handle: ctypes.c_void_p) -> "SpinFilter":
        f = cls.__new__(cls)
        f._handle = handle
        return f

    def clone(self) -> "SpinFilter":
        """An independent copy (state and cached noise parameters)."""
        handle = ctypes.c_void_p()
        _check(lib().bingham_spin_filter_clone(self._h(), ctypes.byref(handle)))
        return SpinFilter._adopt(handle)

    def step(
        self,
        m_w: ArrayLike,
        z_w: ArrayLike,
        y: Optional[ArrayLike] = None,
        m_o: Optional[ArrayLike] = None,
        z_o: Optional[ArrayLike] = None,
        *,
        u: Optional[ArrayLike] = None,
    ) -> None:
        """One time step: ``v ← w ∘ u ∘ v``, ``x ← v ∘ x`` (the previous spin), then, if ``y``
        is given, the observation ``y = o ∘ x``, o ~ Bingham(m_o, z_o) (the sign of ``y`` does
        not matter). ``y=None``: nothing observed this step (prediction only; ``m_o`` and
        ``z_o`` are then ignored). ``u``: the control, a known change of spin (unit
        quaternion), or ``None``. Pass the same noise arrays every step: the library caches
        them by value."""
        u_arr = None if u is None else _in(u, "u", (4,))
        m_w, z_w = _dist4(m_w, z_w, ("m_w", "z_w"))
        y_arr: Optional[Array] = None
        mo: Optional[Array] = None
        zo: Optional[Array] = None
        if y is not None:
            if m_o is None or z_o is None:
                raise ValueError("an observation y needs its noise m_o and z_o")
            y_arr = _in(y, "y", (4,))
            mo, zo = _dist4(m_o, z_o, ("m_o", "z_o"))
        _check(
            lib().bingham_spin_filter_step(
                self._h(), _ptr(u_arr), _ptr(m_w), _ptr(z_w), _ptr(y_arr), _ptr(mo), _ptr(zo)
            )
        )

    def log_likelihood(self, y: ArrayLike, m_o: ArrayLike, z_o: ArrayLike) -> float:
        """The log predictive density of observing ``y = o ∘ x`` at the step about to be taken
        (before :meth:`step`; surface measure on S³; the filter is not changed). A bank of spin
        filters sums it over time to compare its hypotheses; of two readings of an ambiguous
        observation, the one with the larger value is the more probable. The first call after
        a step computes the orientation's prediction and the filter keeps it, so a second call
        and the next :meth:`step` reuse it."""
        y = _in(y, "y", (4,))
        m_o, z_o = _dist4(m_o, z_o, ("m_o", "z_o"))
        out = np.empty(1)
        _check(lib().bingham_spin_filter_log_likelihood(self._h(), _ptr(y), _ptr(m_o), _ptr(z_o), _ptr(out)))
        return float(out[0])

    def state(self) -> Tuple[Array, Array, Array, Array]:
        """Both marginals ``(m_x, z_x, m_v, z_v)``: z ascending with z[-1] = 0, the last column
        of m the mode."""
        m_x, z_x, m_v, z_v = np.empty((4, 4)), np.empty(4), np.empty((4, 4)), np.empty(4)
        _check(lib().bingham_spin_filter_get_state(self._h(), _ptr(m_x), _ptr(z_x), _ptr(m_v), _ptr(z_v)))
        return m_x, z_x, m_v, z_v

    def orientation(self) -> Tuple[Array, Array]:
        """The orientation's marginal ``(m_x, z_x)``."""
        m_x, z_x, _, _ = self.state()
        return m_x, z_x

    def spin(self) -> Tuple[Array, Array]:
        """The spin's marginal ``(m_v, z_v)`` (the rotation per step)."""
        _, _, m_v, z_v = self.state()
        return m_v, z_v

    def set_state(self, m_x: ArrayLike, z_x: ArrayLike, m_v: ArrayLike, z_v: ArrayLike) -> None:
        """Replaces both marginals (re-initialization; the cached noises stay)."""
        m_x, z_x = _dist4(m_x, z_x, ("m_x", "z_x"))
        m_v, z_v = _dist4(m_v, z_v, ("m_v", "z_v"))
        _check(lib().bingham_spin_filter_set_state(self._h(), _ptr(m_x), _ptr(z_x), _ptr(m_v), _ptr(z_v)))

    def orientation_mode(self) -> Array:
        """The orientation estimate, a unit quaternion (its negative is the same rotation)."""
        out = np.empty(4)
        _check(lib().bingham_spin_filter_orientation_mode(self._h(), _ptr(out)))
        return out

    def spin_mode(self) -> Array:
        """The spin estimate: the most probable rotation per step, a unit quaternion (its
        rotation angle divided by the step's duration is the angular rate)."""
        out = np.empty(4)
        _check(lib().bingham_spin_filter_spin_mode(self._h(), _ptr(out)))
        return out

    def angular_spread(self) -> Tuple[Array, Array]:
        """The angular spreads ``(x_spread, v_spread)`` in radians (the spin's per step), 4
        entries each: along the marginal's principal directions (columns 0–2 of m), then the
        total (see :func:`angular_spread`)."""
        xs, vs = np.empty(4), np.empty(4)
        _check(lib().bingham_spin_filter_angular_spread(self._h(), _ptr(xs), _ptr(vs)))
        return xs, vs
