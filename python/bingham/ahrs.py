"""The Bingham AHRS: :class:`Ahrs`, owning a ``bingham_ahrs`` handle (gyroscope,
accelerometer, optional magnetometer), and its parameters :class:`AhrsParams`."""

from __future__ import annotations

import ctypes
from typing import Dict, Optional, Tuple, Union

import numpy as np

from ._arrays import Array, ArrayLike, _in, _ptr
from .errors import Status, _check
from ._library import lib

__all__ = ["AhrsParams", "Ahrs", "LATENCY_ESTIMATE"]

#: ``mag_latency`` value (the default) that compensates the AHRS's online estimate of the
#: magnetometer's latency (``BINGHAM_AHRS_LATENCY_ESTIMATE`` in C).
LATENCY_ESTIMATE = -1.0


class AhrsParams(ctypes.Structure):
    """``bingham_ahrs_params`` (all angles in radians, times in seconds); build it with
    :meth:`default`, which gives the tuned defaults. ``mag_latency`` / ``acc_latency`` (s, 0 to
    0.5, default 0): the magnetometer's / accelerometer's latency behind the gyroscope, each
    sample turned forward by the rate over it (see :meth:`Ahrs.mag_latency_estimate`).
    ``bias_std`` (rad/s, > 0, default 0.5°/s): the initial standard deviation per axis of the
    gyroscope bias, where its covariance starts (see :meth:`Ahrs.gyro_bias_covariance`).
    ``gyro_scale_noise`` (√s, >= 0, default about 0.01): process noise per rad/s of rotation
    rate, the orientation's noise variance growing by ``(gyro_scale_noise·|ω|)²`` per second
    (scale-factor and misalignment errors of the gyroscope)."""

    _fields_ = [
        ("sample_time", ctypes.c_double),
        ("gyro_noise", ctypes.c_double),
        ("acc_noise", ctypes.c_double),
        ("acc_reject", ctypes.c_double),
        ("acc_tau", ctypes.c_double),
        ("mag_tau", ctypes.c_double),
        ("gravity", ctypes.c_double),
        ("mag_noise", ctypes.c_double),
        ("mag_norm_tol", ctypes.c_double),
        ("mag_dip_tol", ctypes.c_double),
        ("mag_ref_time", ctypes.c_double),
        ("mag_new_time", ctypes.c_double),
        ("bias_time", ctypes.c_double),
        ("bias_max", ctypes.c_double),
        ("rest_time", ctypes.c_double),
        ("rest_gyro", ctypes.c_double),
        ("rest_acc", ctypes.c_double),
        ("rest_bias_time", ctypes.c_double),
        ("init_std", ctypes.c_double),
        ("mag_latency", ctypes.c_double),
        ("acc_latency", ctypes.c_double),
        ("bias_std", ctypes.c_double),
        ("gyro_scale_noise", ctypes.c_double),
    ]

    @classmethod
    def default(cls, sample_time: float) -> "AhrsParams":
        """The library's tuned defaults for the sample time ``sample_time`` (seconds)."""
        p = cls()
        _check(lib().bingham_ahrs_params_default(float(sample_time), ctypes.byref(p)))
        return p

    def as_dict(self) -> Dict[str, float]:
        """The parameters as a ``{name: value}`` dictionary."""
        return {name: getattr(self, name) for name, *_ in self._fields_}


def _rows3(a: ArrayLike, name: str, n: Optional[int] = None) -> Array:
    arr = _in(a, name)
    if arr.ndim != 2 or arr.shape[1] != 3 or (n is not None and arr.shape[0] != n):
        want = f"({n if n is not None else 'n'}, 3)"
        raise ValueError(f"{name} must have shape {want}, got {arr.shape}")
    return arr


class Ahrs:
    """The Bingham AHRS (gyroscope, accelerometer, optional magnetometer), owning a
    ``bingham_ahrs`` handle. Orientation q (w, x, y, z) maps sensor to world ENU.
    Units: rad/s, m/s² (+g up at rest), any magnetometer unit.

    ``Ahrs(sample_time)`` uses the tuned defaults; pass ``params=`` (an :class:`AhrsParams`)
    or keyword overrides (``Ahrs(0.01, acc_noise=0.8)``) to change them.
    """

    def __init__(self, sample_time: float, params: Optional[AhrsParams] = None, **overrides: float) -> None:
        p = AhrsParams.default(sample_time) if params is None else params
        for k, v in overrides.items():
            if k not in p.as_dict():
                raise TypeError(f"unknown AHRS parameter {k!r}")
            setattr(p, k, float(v))
        handle = ctypes.c_void_p()
        _check(lib().bingham_ahrs_new(ctypes.byref(p), ctypes.byref(handle)))
        self._handle: Optional[ctypes.c_void_p] = handle
        self.params = p

    def close(self) -> None:
        """Releases the handle (idempotent)."""
        if getattr(self, "_handle", None) is not None:
            lib().bingham_ahrs_free(self._handle)
            self._handle = None

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:
            pass

    def __enter__(self) -> "Ahrs":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _h(self) -> ctypes.c_void_p:
        if self._handle is None:
            raise ValueError("the AHRS has been closed")
        return self._handle

    def update(self, gyr: ArrayLike, acc: ArrayLike, mag: Optional[ArrayLike] = None) -> None:
        """One sample (3-vectors; ``mag`` may be None). Per channel: NaN (or ±Inf) in ``acc``
        or ``mag`` means "no sample" of that sensor at this time (not an error); NaN/Inf in
        ``gyr`` refuses the sample (:class:`BinghamError`, the AHRS unchanged), and so does a
        first sample without a finite accelerometer showing gravity."""
        g = _in(gyr, "gyr", (3,))
        a = _in(acc, "acc", (3,))
        m = None if mag is None else _in(mag, "mag", (3,))
        _check(lib().bingham_ahrs_update(self._h(), _ptr(g), _ptr(a), _ptr(m)))

    def update_batch(
        self, gyr: ArrayLike, acc: ArrayLike, mag: Optional[ArrayLike] = None, spread: bool = False
    ) -> Union[Array, Tuple[Array, Array]]:
        """n samples (n×3 arrays; ``mag`` n×3 or None). Returns the n×4 quaternions after each
        sample, or ``(quat, spread)`` with the total angular spread (radians, length n) when
        ``spread`` is true. Per channel, as in :meth:`update`: a row of ``acc`` or ``mag``
        holding NaN means "no sample" of that sensor at that time (fill the rows of a slower or
        gappy sensor with NaN); every row of ``gyr`` must be finite. A refused sample raises
        :class:`BinghamError` (its message names the sample, "sample k: ..."); the samples
        before it have been processed."""
        g = _rows3(gyr, "gyr")
        n = g.shape[0]
        a = _rows3(acc, "acc", n)
        m = None if mag is None else _rows3(mag, "mag", n)
        q = np.empty((n, 4))
        s = np.empty(n) if spread else None
        _check(
            lib().bingham_ahrs_update_batch_spread(
                self._h(), n, _ptr(g), _ptr(a), _ptr(m), _ptr(q), _ptr(s)
            )
        )
        if s is not None:
            return q, s
        return q

    def quaternion(self) -> Array:
        """The estimate (w, x, y, z), sensor → world ENU, w ≥ 0."""
        out = np.empty(4)
        _check(lib().bingham_ahrs_quaternion(self._h(), _ptr(out)))
        return out

    def state(self) -> Tuple[Array, Array]:
        """The Bingham state ``(m, z)`` of the orientation."""
        m = np.empty((4, 4))
        z = np.empty(4)
        _check(lib().bingham_ahrs_state(self._h(), _ptr(m), _ptr(z)))
        return m, z

    def set_state(self, m: ArrayLike, z: ArrayLike) -> None:
        """Replaces the orientation estimate by Bingham(m, z) (a known start or a reset)."""
        m = _in(m, "m", (4, 4))
        z = _in(z, "z", (4,))
        _check(lib().bingham_ahrs_set_state(self._h(), _ptr(m), _ptr(z)))

    def angular_spread(self) -> Array:
        """Angular spread (radians): 3 principal axes, then the total."""
        out = np.empty(4)
        _check(lib().bingham_ahrs_angular_spread(self._h(), _ptr(out)))
        return out

    def gyro_bias(self) -> Array:
        """The gyroscope bias estimate (rad/s, sensor frame)."""
        out = np.empty(3)
        _check(lib().bingham_ahrs_gyro_bias(self._h(), _ptr(out)))
        return out

    def gyro_bias_covariance(self) -> Array:
        """The covariance of the gyroscope bias estimate ((rad/s)², sensor frame) as a 3×3
        array, symmetric positive semi-definite: ``bias_std²·I`` on creation, then shrinking
        as motion and rests teach the bias."""
        out = np.empty((3, 3))
        _check(lib().bingham_ahrs_gyro_bias_covariance(self._h(), _ptr(out)))
        return out

    def mag_latency_estimate(self) -> Optional[float]:
        """The online estimate of the magnetometer's latency behind the gyroscope (seconds,
        0 to 40 ms or 32 samples, whichever is smaller), from the IMU alone; ``None`` until
        5 s of informative motion (a changing rotation rate with an undisturbed magnetometer)
        have been seen. A readout: pass it as ``mag_latency`` to compensate the latency."""
        out = np.empty(1)
        st = lib().bingham_ahrs_mag_latency_estimate(self._h(), _ptr(out))
        if st == Status.ERR_NOT_CONVERGED:
            return None
        _check(st)
        return float(out[0])
