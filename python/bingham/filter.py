"""The recursive Bingham filter: :class:`Filter`, owning a ``bingham_filter`` handle (linear
and nonlinear prediction, measurement updates, likelihoods)."""

from __future__ import annotations

import ctypes
from dataclasses import dataclass
from typing import Any, Callable, Optional, Tuple

import numpy as np

from ._arrays import Array, ArrayLike, _dist, _in, _ptr
from ._callback import _Callback
from .errors import _check
from ._handle import _Handle
from ._library import _LOG_LIKELIHOOD_FN, _SIZE, _TRANSITION_FN, lib

__all__ = ["Filter", "NonlinearReport", "PREDICT_TOLERANCE", "UPDATE_TOLERANCE"]

#: The nonlinear prediction's default tolerance (``BINGHAM_NONLINEAR_PREDICT_TOLERANCE``): the
#: largest accepted error estimate of any entry of the predicted second moment.
PREDICT_TOLERANCE = 5e-4
#: The nonlinear update's default tolerance (``BINGHAM_NONLINEAR_UPDATE_TOLERANCE``).
UPDATE_TOLERANCE = 2.5e-3


class _Options(ctypes.Structure):
    _fields_ = [
        ("tolerance", ctypes.c_double),
        ("mode_tolerance", ctypes.c_double),
        ("max_calls", _SIZE),
    ]


class _Report(ctypes.Structure):
    _fields_ = [
        ("calls", _SIZE),
        ("error_estimate", ctypes.c_double),
        ("mode_error_estimate", ctypes.c_double),
        ("method", ctypes.c_int),
        ("samples", _SIZE),
        ("effective_share", ctypes.c_double),
    ]


@dataclass(frozen=True)
class NonlinearReport:
    """What a nonlinear step measured (``bingham_nonlinear_report``).

    ``calls``: callback calls made; ``error_estimate``: the error estimate of the result's
    second moment (largest entry, absolute; at most the tolerance); ``mode_error_estimate``:
    the update's mode error estimate as a fraction of the posterior's spread (0 for the
    prediction); ``method``: ``"deterministic"`` or ``"sampled"``; ``samples``: sampled points
    behind the result; ``effective_share``: the final importance weights' effective share.
    """

    calls: int
    error_estimate: float
    mode_error_estimate: float
    method: str
    samples: int
    effective_share: float


def _options(tolerance: Optional[float], mode_tolerance: Optional[float], max_calls: Optional[int]) -> _Options:
    o = _Options()
    _check(lib().bingham_nonlinear_options_default(ctypes.byref(o)))
    if tolerance is not None:
        o.tolerance = float(tolerance)
    if mode_tolerance is not None:
        o.mode_tolerance = float(mode_tolerance)
    if max_calls is not None:
        if int(max_calls) < 0:
            raise ValueError(f"max_calls must be non-negative, got {max_calls}")
        o.max_calls = int(max_calls)
    return o


def _report(r: _Report) -> NonlinearReport:
    return NonlinearReport(
        calls=int(r.calls),
        error_estimate=float(r.error_estimate),
        mode_error_estimate=float(r.mode_error_estimate),
        method="deterministic" if r.method == 0 else "sampled",
        samples=int(r.samples),
        effective_share=float(r.effective_share),
    )


class Filter(_Handle):
    """The recursive Bingham filter (d = 2: axes as ``(re, im)``; d = 4: unit quaternions,
    scalar first), owning a ``bingham_filter`` handle.

    System ``x[k+1] = x[k] ⊕ w[k]``, measurement ``z[k] = x[k] ⊕ v[k]`` with Bingham noises
    given as ``(m, z)`` pairs; the world-frame model of Glover & Kaelbling,
    ``x[k+1] = w ∘ u ∘ x[k]``, ``y = v ∘ x`` (noises on the left), with :meth:`predict_world`,
    :meth:`update_world` and :meth:`log_likelihood_world`; nonlinear models
    ``x[k+1] = a(x[k]) ⊕ w[k]`` and any likelihood through Python callables
    (:meth:`predict_nonlinear`, :meth:`update_nonlinear`). A failed call raises
    :class:`BinghamError` and leaves the filter unchanged. Use one filter per thread at a time;
    :meth:`clone` gives an independent copy.
    The handle is released by :meth:`close`, by leaving a ``with`` block, or when the object
    is garbage collected.
    """

    _free = "bingham_filter_free"
    _what = "filter"

    def __init__(self, m0: ArrayLike, z0: ArrayLike) -> None:
        d, m0, z0 = _dist(m0, z0, ("m0", "z0"))
        handle = ctypes.c_void_p()
        _check(lib().bingham_filter_new(d, _ptr(m0), _ptr(z0), ctypes.byref(handle)))
        self._handle: Optional[ctypes.c_void_p] = handle
        self._busy = False
        self.d = d

    @classmethod
    def _adopt(cls, handle: ctypes.c_void_p, d: int) -> "Filter":
        f = cls.__new__(cls)
        f._handle = handle
        f._busy = False
        f.d = d
        return f

    def _h(self) -> ctypes.c_void_p:
        handle = super()._h()
        if self._busy:
            raise ValueError("the filter is in a nonlinear step: its callback must not use it")
        return handle

    def close(self) -> None:
        """Releases the handle (idempotent)."""
        if getattr(self, "_busy", False):
            raise ValueError("the filter is in a nonlinear step: its callback must not close it")
        super().close()

    def clone(self) -> "Filter":
        """An independent copy (state and cached noise parameters)."""
        handle = ctypes.c_void_p()
        _check(lib().bingham_filter_clone(self._h(), ctypes.byref(handle)))
        return Filter._adopt(handle, self.d)

    def dim(self) -> int:
        """The dimension as reported by the library (2 or 4)."""
        d = _SIZE(0)
        _check(lib().bingham_filter_dim(self._h(), ctypes.byref(d)))
        return d.value

    def state(self) -> Tuple[Array, Array]:
        """The estimate ``(m, z)``: z ascending with z[-1] = 0, the last column of m the mode."""
        m = np.empty((self.d, self.d))
        z = np.empty(self.d)
        _check(lib().bingham_filter_get_state(self._h(), _ptr(m), _ptr(z)))
        return m, z

    def set_state(self, m: ArrayLike, z: ArrayLike) -> None:
        """Replaces the estimate by Bingham(m, z)."""
        m = _in(m, "m", (self.d, self.d))
        z = _in(z, "z", (self.d,))
        _check(lib().bingham_filter_set_state(self._h(), _ptr(m), _ptr(z)))

    def mode(self) -> Array:
        """The point estimate (a unit vector; its negative is the same axis / rotation)."""
        out = np.empty(self.d)
        _check(lib().bingham_filter_mode(self._h(), _ptr(out)))
        return out

    def _noise(self, m: ArrayLike, z: ArrayLike, names: Tuple[str, str]) -> Tuple[Array, Array]:
        return _in(m, names[0], (self.d, self.d)), _in(z, names[1], (self.d,))

    def predict(self, m_w: ArrayLike, z_w: ArrayLike) -> None:
        """Prediction with process noise Bingham(m_w, z_w)."""
        m_w, z_w = self._noise(m_w, z_w, ("m_w", "z_w"))
        _check(lib().bingham_filter_predict(self._h(), _ptr(m_w), _ptr(z_w)))

    def predict_rotation(self, u: ArrayLike, m_w: ArrayLike, z_w: ArrayLike) -> None:
        """Prediction of ``x ⊕ u ⊕ w`` for a known unit ``u`` (e.g. a gyroscope increment)."""
        u = _in(u, "u", (self.d,))
        m_w, z_w = self._noise(m_w, z_w, ("m_w", "z_w"))
        _check(lib().bingham_filter_predict_rotation(self._h(), _ptr(u), _ptr(m_w), _ptr(z_w)))

    def predict_nonlinear(
        self,
        fn: Callable[[Array], ArrayLike],
        m_w: ArrayLike,
        z_w: ArrayLike,
        *,
        tolerance: Optional[float] = None,
        max_calls: Optional[int] = None,
    ) -> NonlinearReport:
        """Nonlinear prediction ``x[k+1] = fn(x[k]) ⊕ w[k]``, w ~ Bingham(m_w, z_w).

        ``fn`` is called at the deterministic samples of the state (19 calls for d = 4, 3 for
        d = 2) and, where their error estimate asks for more, at sampled points. The result's
        error estimate (3 standard errors of any entry of the predicted second moment) meets
        ``tolerance`` (default :data:`PREDICT_TOLERANCE`); if that would take more than
        ``max_calls`` calls (default 20000), :class:`BinghamError` with status
        ``ERR_NOT_CONVERGED`` is raised and the filter is unchanged. Returns a
        :class:`NonlinearReport`. The method: docs/design.md, "Nonlinear steps".

        ``fn`` is called with a unit vector
        ``x`` (a NumPy array of length d, a copy the callable may keep) and must return a unit
        vector of length d (any array-like; unit within ``UNIT_TOL``, then normalized). Its sign
        does not matter, and ``fn(-x) = ±fn(x)`` is the caller's contract (``q`` and ``-q`` are
        the same rotation). The weighted second moment of the results is composed exactly with
        the noise and refitted; with ``fn`` the identity this is :meth:`predict`.

        ``fn`` must not use this filter (that raises ``ValueError`` inside it). If ``fn`` raises,
        or returns a wrong shape or a non-finite or non-unit vector, the filter is unchanged and
        :class:`BinghamError` with status ``ERR_CALLBACK`` is raised (``from`` the callable's
        exception, if any: see ``__cause__``).
        """
        m_w, z_w = self._noise(m_w, z_w, ("m_w", "z_w"))
        opts = _options(tolerance, None, max_calls)
        rep = _Report()
        d = self.d
        guard = _Callback()

        def call(x_in: Any, x_out: Any) -> None:
            x = np.ctypeslib.as_array(x_in, shape=(d,)).copy()
            y = np.ascontiguousarray(fn(x), dtype=np.float64)
            if y.shape != (d,):
                raise ValueError(f"the transition must return shape ({d},), got {y.shape}")
            ctypes.memmove(x_out, y.ctypes.data, d * ctypes.sizeof(ctypes.c_double))

        cb = _TRANSITION_FN(lambda x_in, x_out, _user: guard.run(lambda: call(x_in, x_out)))
        handle = self._h()
        self._busy = True
        try:
            status = lib().bingham_filter_predict_nonlinear_opts(
                handle, cb, None, _ptr(m_w), _ptr(z_w), ctypes.byref(opts), ctypes.byref(rep)
            )
        finally:
            self._busy = False
        guard.check(status)
        return _report(rep)

    def update_nonlinear(
        self,
        log_likelihood: Callable[[Array], float],
        *,
        tolerance: Optional[float] = None,
        mode_tolerance: Optional[float] = None,
        max_calls: Optional[int] = None,
    ) -> NonlinearReport:
        """Nonlinear Bayes update: posterior ∝ prior(x) · L(x), ``log_likelihood(x)`` = log L(x).

        The posterior is approximated by a Bingham distribution and every update is checked by
        sampling: 3 standard errors of every entry of its second moment meet ``tolerance``
        (default :data:`UPDATE_TOLERANCE`) and those of the mode ``mode_tolerance`` (default
        0.05) of the posterior's spread; if that would take more than ``max_calls`` calls
        (default 20000), :class:`BinghamError` with status ``ERR_NOT_CONVERGED`` is raised (its
        message gives the estimate reached) and the filter is unchanged. Returns a
        :class:`NonlinearReport`. The method: docs/design.md, "Nonlinear steps".

        ``log_likelihood`` gets a unit vector ``x`` (a NumPy array of length d, a copy) and
        returns a finite float; ``L(-x) = L(x)`` is the caller's contract. A Bingham likelihood
        stays exact, but :meth:`update` and :func:`multiply` compute it without callbacks.

        ``log_likelihood`` must not use this filter. If it raises or returns a non-finite value,
        the filter is unchanged and :class:`BinghamError` with status ``ERR_CALLBACK`` is raised
        (``from`` the callable's exception, if any).
        """
        opts = _options(tolerance, mode_tolerance, max_calls)
        rep = _Report()
        d = self.d
        guard = _Callback()

        def call(x_in: Any, log_l: Any) -> None:
            x = np.ctypeslib.as_array(x_in, shape=(d,)).copy()
            log_l[0] = float(log_likelihood(x))

        cb = _LOG_LIKELIHOOD_FN(lambda x_in, log_l, _user: guard.run(lambda: call(x_in, log_l)))
        handle = self._h()
        self._busy = True
        try:
            status = lib().bingham_filter_update_nonlinear_opts(
                handle, cb, None, ctypes.byref(opts), ctypes.byref(rep)
            )
        finally:
            self._busy = False
        guard.check(status)
        return _report(rep)

    def update(self, measurement: ArrayLike, m_v: ArrayLike, z_v: ArrayLike) -> None:
        """Measurement update with ``measurement = x ⊕ v``, v ~ Bingham(m_v, z_v)."""
        meas = _in(measurement, "measurement", (self.d,))
        m_v, z_v = self._noise(m_v, z_v, ("m_v", "z_v"))
        _check(lib().bingham_filter_update(self._h(), _ptr(meas), _ptr(m_v), _ptr(z_v)))

    def log_likelihood(self, measurement: ArrayLike, m_v: ArrayLike, z_v: ArrayLike) -> float:
        """Log predictive density of a measurement (the filter is not changed)."""
        meas = _in(measurement, "measurement", (self.d,))
        m_v, z_v = self._noise(m_v, z_v, ("m_v", "z_v"))
        out = np.empty(1)
        _check(
            lib().bingham_filter_log_likelihood(self._h(), _ptr(meas), _ptr(m_v), _ptr(z_v), _ptr(out))
        )
        return float(out[0])

    def surprise(self, measurement: ArrayLike, m_v: ArrayLike, z_v: ArrayLike) -> float:
        """The measurement's surprise ``2 (log p(ŷ) − log p(measurement)) ≥ 0`` (``ŷ`` the
        predicted measurement, the modes of state and noise composed): a χ² variable with d − 1
        degrees of freedom when the model holds and state and noise are concentrated (mean 3
        for quaternions, above 16.27 with probability 0.1 %; d = 2: mean 1, above 10.83 with
        0.1 %). A fix in the wrong component order scores hundreds. The filter is not changed."""
        meas = _in(measurement, "measurement", (self.d,))
        m_v, z_v = self._noise(m_v, z_v, ("m_v", "z_v"))
        out = np.empty(1)
        _check(lib().bingham_filter_surprise(self._h(), _ptr(meas), _ptr(m_v), _ptr(z_v), _ptr(out)))
        return float(out[0])

    def update_gated(
        self, measurement: ArrayLike, m_v: ArrayLike, z_v: ArrayLike, max_surprise: float
    ) -> Tuple[bool, float]:
        """:meth:`update` if the measurement's :meth:`surprise` is at most ``max_surprise``
        (≥ 0; ``math.inf``: no gate), otherwise nothing changes. Returns ``(accepted,
        surprise)``; a gated-out measurement is not an error."""
        meas = _in(measurement, "measurement", (self.d,))
        m_v, z_v = self._noise(m_v, z_v, ("m_v", "z_v"))
        out = np.empty(1)
        accepted = ctypes.c_int32(0)
        _check(
            lib().bingham_filter_update_gated(
                self._h(), _ptr(meas), _ptr(m_v), _ptr(z_v), float(max_surprise), _ptr(out),
                ctypes.byref(accepted),
            )
        )
        return bool(accepted.value), float(out[0])

    def predict_world(self, m_w: ArrayLike, z_w: ArrayLike, *, u: Optional[ArrayLike] = None) -> None:
        """World-frame prediction (Glover & Kaelbling 2013): the state becomes the distribution
        of ``w ∘ u ∘ x``, w ~ Bingham(m_w, z_w), where ``q ∘ r`` is the Hamilton product ``q r``
        ("rotate by r, then by q"): the control ``u`` (a known unit rotation, applied exactly;
        ``None``: the identity) and the noise act on the left, in the world frame, where
        :meth:`predict_rotation` composes on the right (body frame). The two agree for d = 2 and,
        without ``u``, for noise isotropic about the identity. Exact in the second moment."""
        u_arr = None if u is None else _in(u, "u", (self.d,))
        m_w, z_w = self._noise(m_w, z_w, ("m_w", "z_w"))
        _check(lib().bingham_filter_predict_world(self._h(), _ptr(u_arr), _ptr(m_w), _ptr(z_w)))

    def update_world(self, y: ArrayLike, m_v: ArrayLike, z_v: ArrayLike) -> None:
        """World-frame update (exact Bayes product) with the observation ``y = v ∘ x``,
        v ~ Bingham(m_v, z_v) (the noise on the left; :meth:`update` has ``x ⊕ v``). The sign of
        ``y`` does not matter."""
        y = _in(y, "y", (self.d,))
        m_v, z_v = self._noise(m_v, z_v, ("m_v", "z_v"))
        _check(lib().bingham_filter_update_world(self._h(), _ptr(y), _ptr(m_v), _ptr(z_v)))

    def log_likelihood_world(self, y: ArrayLike, m_v: ArrayLike, z_v: ArrayLike) -> float:
        """Log predictive density of ``y = v ∘ x`` (surface measure; the filter is not changed):
        what a bank of filters sums, and what picks between the readings of an ambiguous ``y``."""
        y = _in(y, "y", (self.d,))
        m_v, z_v = self._noise(m_v, z_v, ("m_v", "z_v"))
        out = np.empty(1)
        _check(
            lib().bingham_filter_log_likelihood_world(self._h(), _ptr(y), _ptr(m_v), _ptr(z_v), _ptr(out))
        )
        return float(out[0])

    def update_vector(self, body: ArrayLike, reference: ArrayLike, kappa: float) -> None:
        """Update (d = 4) with a measured direction ``body`` (sensor frame, unit) of the known
        ``reference`` (world frame, unit), von Mises–Fisher noise of concentration ``kappa``."""
        b = _in(body, "body", (3,))
        r = _in(reference, "reference", (3,))
        _check(lib().bingham_filter_update_vector(self._h(), _ptr(b), _ptr(r), float(kappa)))

    def log_likelihood_vector(self, body: ArrayLike, reference: ArrayLike, kappa: float) -> float:
        """Log predictive density of a measured direction (d = 4; the filter is not changed)."""
        b = _in(body, "body", (3,))
        r = _in(reference, "reference", (3,))
        out = np.empty(1)
        _check(
            lib().bingham_filter_log_likelihood_vector(
                self._h(), _ptr(b), _ptr(r), float(kappa), _ptr(out)
            )
        )
        return float(out[0])

    def angular_spread(self) -> Array:
        """The state's angular spread in radians (see :func:`angular_spread`), length d."""
        out = np.empty(self.d)
        _check(lib().bingham_filter_angular_spread(self._h(), _ptr(out)))
        return out
