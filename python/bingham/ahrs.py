"""The Bingham AHRS: :class:`Ahrs`, owning a ``bingham_ahrs`` handle (gyroscope,
accelerometer, optional magnetometer), and its parameters :class:`AhrsParams`."""

from __future__ import annotations

import ctypes
import math
from typing import Dict, Optional, Tuple, Union

import numpy as np

from ._arrays import Array, ArrayLike, _in, _ptr
from .errors import Status, _check, last_error_message
from ._handle import _Handle
from ._library import lib

__all__ = ["AhrsParams", "AhrsHealth", "Ahrs", "LATENCY_ESTIMATE", "HEALTH_THRESHOLD", "HEALTH_TIME"]

#: ``mag_latency`` value (the default) that compensates the AHRS's online estimate of the
#: magnetometer's latency (``BINGHAM_AHRS_LATENCY_ESTIMATE`` in C).
LATENCY_ESTIMATE = -1.0

#: The health score above which the input is likely wrong (``BINGHAM_AHRS_HEALTH_THRESHOLD``):
#: see :meth:`Ahrs.health`.
HEALTH_THRESHOLD = 10.0

#: The time constant (s) of the health averages (``BINGHAM_AHRS_HEALTH_TIME``).
HEALTH_TIME = 5.0


class AhrsHealth(ctypes.Structure):
    """``bingham_ahrs_health_report``, the AHRS's health readout (see :meth:`Ahrs.health`).

    ``score``: the largest of ``gravity_score``, ``tilt_score`` and ``heading_score``, about 1
    (or less) when the sensors agree with the model, above :data:`HEALTH_THRESHOLD` (10) an
    input mistake is likely (a gyroscope in °/s, a wrong sample time); ``tilt_innovation`` and
    ``heading_innovation`` (rad) at the last correction; ``mag_rejected`` the fraction of
    magnetometer samples refused as disturbed over the last :data:`HEALTH_TIME` seconds;
    ``mag_dip`` (rad, positive below the horizon) the reference field's dip, valid when
    ``has_mag_reference`` is 1 — of the wrong sign for the place (negative north of the
    magnetic equator), the accelerometer's sign is flipped; ``gyr_missing_time``,
    ``acc_missing_time``, ``mag_missing_time`` the seconds since each sensor's last usable
    sample (0 when the last sample had one; the magnetometer's counted from the first sample
    if it was never seen). All zero before the first correction. Definitions: docs/guide.md,
    "Health readout"."""

    _fields_ = [
        ("score", ctypes.c_double),
        ("gravity_score", ctypes.c_double),
        ("tilt_score", ctypes.c_double),
        ("heading_score", ctypes.c_double),
        ("tilt_innovation", ctypes.c_double),
        ("heading_innovation", ctypes.c_double),
        ("mag_rejected", ctypes.c_double),
        ("mag_dip", ctypes.c_double),
        ("has_mag_reference", ctypes.c_int32),
        ("gyr_missing_time", ctypes.c_double),
        ("acc_missing_time", ctypes.c_double),
        ("mag_missing_time", ctypes.c_double),
    ]

    def __repr__(self) -> str:
        body = ", ".join(f"{name}={getattr(self, name)!r}" for name, *_ in self._fields_)
        return f"AhrsHealth({body})"


class AhrsParams(ctypes.Structure):
    """``bingham_ahrs_params`` (all angles in radians, times in seconds).

    Build it in one of two ways, both starting from the library's tuned defaults for the sample
    time: :meth:`default` (``AhrsParams.default(0.01)``), or keywords naming ``sample_time`` and
    the fields to change (``AhrsParams(sample_time=0.01, acc_noise=0.8)``). Positional
    arguments, a missing ``sample_time`` or an unknown field name raise :class:`TypeError` (a
    structure of zeros is not a valid parameter set). :meth:`copy` gives an independent copy;
    :class:`Ahrs` never modifies the instance it is given.

    The fields, their units and defaults are those of the C struct (docs/guide.md, "The
    defaults and why"); what each means and why its default: docs/design.md, "AHRS"
    ("Parameters"). For example ``mag_latency`` / ``acc_latency`` (s, 0 to 0.5; defaults
    :data:`LATENCY_ESTIMATE` and 0): the magnetometer's / accelerometer's latency behind the
    gyroscope (see :meth:`Ahrs.mag_latency_estimate`); ``bias_std`` (rad/s, > 0, default
    0.5°/s): the initial standard deviation per axis of the gyroscope bias (see
    :meth:`Ahrs.gyro_bias_covariance`); ``gyro_scale_noise`` (√s, >= 0, default 0.004): process
    noise per rad/s of rotation rate; ``gyro_scale_std`` (relative, 0 to 0.05, default 0.001):
    the initial standard deviation per axis of the gyroscope's scale error, estimated with the
    bias (0: not estimated)."""

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
        ("init_std", ctypes.c_double),
        ("mag_latency", ctypes.c_double),
        ("acc_latency", ctypes.c_double),
        ("bias_std", ctypes.c_double),
        ("gyro_scale_noise", ctypes.c_double),
        ("gyro_scale_std", ctypes.c_double),
    ]

    def __init__(self, *args: object, **fields: float) -> None:
        if args:
            raise TypeError(
                "AhrsParams takes no positional arguments: use AhrsParams.default(sample_time) "
                "or keywords, e.g. AhrsParams(sample_time=0.01, acc_noise=0.8)"
            )
        if "sample_time" not in fields:
            raise TypeError(
                "AhrsParams needs sample_time (seconds), the other fields start from its defaults: "
                "use AhrsParams.default(sample_time) or AhrsParams(sample_time=0.01, acc_noise=0.8)"
            )
        _known_fields(fields)
        _refuse_rate(fields["sample_time"], "AhrsParams")
        ctypes.Structure.__init__(self)
        _check(lib().bingham_ahrs_params_default(float(fields["sample_time"]), ctypes.byref(self)))
        for name, value in fields.items():
            if name != "sample_time":
                setattr(self, name, float(value))

    @classmethod
    def default(cls, sample_time: float) -> "AhrsParams":
        """The library's tuned defaults for the sample time ``sample_time`` (seconds)."""
        return cls(sample_time=sample_time)

    @classmethod
    def from_rate(cls, hz: float) -> "AhrsParams":
        """The library's tuned defaults for the sample rate ``hz`` (samples per second):
        ``AhrsParams.default(1 / hz)`` (``bingham_ahrs_params_from_rate`` in C). ``hz`` must be
        finite and at least 1 (the sample time at most 1 s), else :class:`ValueError`."""
        hz = _check_rate(hz)
        p = cls.from_buffer_copy(bytes(ctypes.sizeof(cls)))  # zeros, filled by the library
        _check(lib().bingham_ahrs_params_from_rate(hz, ctypes.byref(p)))
        return p

    def copy(self) -> "AhrsParams":
        """An independent copy (changing one does not change the other)."""
        return type(self).from_buffer_copy(self)

    def __repr__(self) -> str:
        body = ", ".join(f"{k}={v!r}" for k, v in self.as_dict().items())
        return f"{type(self).__name__}({body})"

    def as_dict(self) -> Dict[str, float]:
        """The parameters as a ``{name: value}`` dictionary."""
        return {name: getattr(self, name) for name, *_ in self._fields_}


_FIELD_NAMES: Tuple[str, ...] = tuple(f[0] for f in AhrsParams._fields_)



def _known_fields(names: Dict[str, float]) -> None:
    unknown = sorted(set(names) - set(_FIELD_NAMES))
    if unknown:
        raise TypeError(
            f"unknown AHRS parameter(s) {', '.join(map(repr, unknown))}; "
            f"valid: {', '.join(_FIELD_NAMES)}"
        )


# The largest ``sample_time`` (seconds) accepted (``BINGHAM_AHRS_MAX_SAMPLE_TIME`` in C): a
# larger value is almost surely a rate in Hz. The library refuses it too; checked here first so
# that the hint names the Python call.
_MAX_SAMPLE_TIME = 1.0


def _check_rate(hz: object) -> float:
    """``hz`` as a float, or :class:`ValueError` if it is not finite, not > 0, or below
    ``1 / _MAX_SAMPLE_TIME`` Hz."""
    hz = float(hz)  # type: ignore[arg-type]
    if not math.isfinite(hz) or hz <= 0.0:
        raise ValueError(f"the sample rate must be finite and > 0 Hz, got {hz!r}")
    if 1.0 / hz > _MAX_SAMPLE_TIME:
        raise ValueError(
            f"the sample rate {hz:g} Hz is below {1.0 / _MAX_SAMPLE_TIME:g} Hz "
            f"(a sample time above {_MAX_SAMPLE_TIME:g} s)"
        )
    return hz


def _refuse_rate(sample_time: object, what: str) -> None:
    """:class:`ValueError` ("did you pass a rate in Hz?") for a finite ``sample_time`` above
    ``_MAX_SAMPLE_TIME``; other values are left to the library."""
    try:
        st = float(sample_time)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return
    if math.isfinite(st) and st > _MAX_SAMPLE_TIME:
        raise ValueError(
            f"{what}: sample_time = {st:g} s: did you pass a rate in Hz? "
            f"use Ahrs.from_rate({st:g}) (sample_time is the period in seconds, "
            f"at most {_MAX_SAMPLE_TIME:g} s)"
        )


def _rows3(a: ArrayLike, name: str, n: Optional[int] = None) -> Array:
    arr = _in(a, name)
    if arr.ndim != 2 or arr.shape[1] != 3 or (n is not None and arr.shape[0] != n):
        want = f"({n if n is not None else 'n'}, 3)"
        raise ValueError(f"{name} must have shape {want}, got {arr.shape}")
    return arr


class Ahrs(_Handle):
    """The Bingham AHRS (gyroscope, accelerometer, optional magnetometer), owning a
    ``bingham_ahrs`` handle. Orientation q (w, x, y, z) maps sensor to world ENU.
    Units: rad/s, m/s² (+g up at rest), any magnetometer unit.

    ``Ahrs(sample_time)`` uses the tuned defaults for the sample time (seconds, the period,
    not the rate: ``Ahrs(0.01)`` or ``Ahrs.from_rate(100)`` for 100 Hz); pass ``params=`` (an
    :class:`AhrsParams`) and/or keyword overrides (``Ahrs(0.01, acc_noise=0.8)``) to change
    them. ``params`` is copied, never modified (the overrides go to the copy, kept as
    ``self.params``), and its ``sample_time`` must equal ``sample_time`` (else
    :class:`ValueError`). A ``sample_time`` above 1 s raises :class:`ValueError` ("did you pass
    a rate in Hz?"), as in :class:`AhrsParams` (the library's bound,
    ``BINGHAM_AHRS_MAX_SAMPLE_TIME``). An unknown
    override raises :class:`TypeError`, a value the library refuses :class:`BinghamError`.
    """

    _free = "bingham_ahrs_free"
    _what = "AHRS"

    def __init__(self, sample_time: float, params: Optional[AhrsParams] = None, **overrides: float) -> None:
        sample_time = float(sample_time)
        _refuse_rate(sample_time, "Ahrs")
        if params is None:
            p = AhrsParams.default(sample_time)
        else:
            if not isinstance(params, AhrsParams):
                raise TypeError(f"params must be an AhrsParams, got {type(params).__name__}")
            if params.sample_time != sample_time:
                raise ValueError(
                    f"sample_time = {sample_time!r} s (the first argument) differs from "
                    f"params.sample_time = {params.sample_time!r} s: pass the same value, e.g. "
                    f"Ahrs(p.sample_time, params=p), or build p for this sample time"
                )
            p = params.copy()
        _known_fields(overrides)
        for k, v in overrides.items():
            setattr(p, k, float(v))
        handle = ctypes.c_void_p()
        _check(lib().bingham_ahrs_new(ctypes.byref(p), ctypes.byref(handle)))
        self._handle: Optional[ctypes.c_void_p] = handle
        #: The parameters in use (a copy: changing it does not change this AHRS).
        self.params = p

    @classmethod
    def from_rate(cls, hz: float, **overrides: float) -> "Ahrs":
        """The AHRS for a sample rate of ``hz`` (samples per second): ``Ahrs(1 / hz,
        **overrides)``, the parameters from :meth:`AhrsParams.from_rate`. ``hz`` must be finite
        and at least 1 (the sample time at most 1 s), else :class:`ValueError`."""
        p = AhrsParams.from_rate(hz)
        return cls(p.sample_time, p, **overrides)

    def update(self, gyr: ArrayLike, acc: ArrayLike, mag: Optional[ArrayLike] = None, dt: Optional[float] = None) -> None:
        """One sample (3-vectors; ``mag`` may be None), taken ``dt`` seconds after the previous
        one (default: the nominal ``sample_time``; ``bingham_ahrs_update_dt``). Per channel:
        NaN (or ±Inf) means "no sample" of that sensor at this time (not an error); a missing
        gyroscope sample is a gap the AHRS carries the orientation through, its uncertainty
        added to the spread. Refused (:class:`BinghamError`, the AHRS unchanged): ``dt`` not in
        1e-6 … 10 s, a first sample without a finite accelerometer showing gravity."""
        g = _in(gyr, "gyr", (3,))
        a = _in(acc, "acc", (3,))
        m = None if mag is None else _in(mag, "mag", (3,))
        if dt is None:
            _check(lib().bingham_ahrs_update(self._h(), _ptr(g), _ptr(a), _ptr(m)))
        else:
            _check(lib().bingham_ahrs_update_dt(self._h(), float(dt), _ptr(g), _ptr(a), _ptr(m)))

    def update_batch(
        self,
        gyr: ArrayLike,
        acc: ArrayLike,
        mag: Optional[ArrayLike] = None,
        spread: bool = False,
        health: bool = False,
        time: Optional[ArrayLike] = None,
    ) -> Union[Array, Tuple[Array, ...]]:
        """n samples (n×3 arrays; ``mag`` n×3 or None). Returns the n×4 quaternions after each
        sample, or a tuple ``(quat, spread)``, ``(quat, health)`` or ``(quat, spread, health)``
        with the total angular spread (radians, length n) when ``spread`` is true and the health
        score (:meth:`health`'s ``score``, length n) when ``health`` is true. ``time``: the n
        timestamps (s, strictly increasing; ``bingham_ahrs_update_batch_timed``), so that each
        sample has its own time step (dropped packets, jitter); the first one's step is from
        the previous timed batch's last timestamp, or the nominal period. Per channel, as in
        :meth:`update`: a row holding NaN means "no sample" of that sensor at that time (fill
        the rows of a slower or gappy sensor with NaN; a NaN gyroscope row is a gap, never an
        error). A refused sample raises :class:`BinghamError` (its message names the sample,
        "sample k: ..."); the samples before it have been processed."""
        g = _rows3(gyr, "gyr")
        n = g.shape[0]
        a = _rows3(acc, "acc", n)
        m = None if mag is None else _rows3(mag, "mag", n)
        q = np.empty((n, 4))
        s = np.empty(n) if spread else None
        h = np.empty(n) if health else None
        if time is None:
            _check(
                lib().bingham_ahrs_update_batch_health(
                    self._h(), n, _ptr(g), _ptr(a), _ptr(m), _ptr(q), _ptr(s), _ptr(h)
                )
            )
        else:
            t = _in(time, "time", (n,))
            _check(
                lib().bingham_ahrs_update_batch_timed(
                    self._h(), n, _ptr(t), _ptr(g), _ptr(a), _ptr(m), _ptr(q), _ptr(s), _ptr(h)
                )
            )
        extra = tuple(x for x in (s, h) if x is not None)
        return (q, *extra) if extra else q

    def health(self) -> AhrsHealth:
        """The health readout: how well the sensors have agreed with the model over the last
        :data:`HEALTH_TIME` (5 s); ``score`` above :data:`HEALTH_THRESHOLD` flags a likely input
        mistake (see :class:`AhrsHealth`; definitions in docs/guide.md, "Health readout")."""
        out = AhrsHealth()
        _check(lib().bingham_ahrs_health(self._h(), ctypes.byref(out)))
        return out

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

    def gyro_scale(self) -> Array:
        """The gyroscope scale-error estimate (relative, per sensor axis: the gyroscope reads
        ``(1 + s_i)`` times the rate about axis ``i``, plus the bias), learned with the bias
        from ``gyro_scale_std``'s prior; zeros when ``gyro_scale_std`` is 0
        (``bingham_ahrs_gyro_scale``)."""
        out = np.empty(3)
        _check(lib().bingham_ahrs_gyro_scale(self._h(), _ptr(out)))
        return out

    def gyro_bias_covariance(self) -> Array:
        """The covariance of the gyroscope bias estimate ((rad/s)², sensor frame) as a 3×3
        array, symmetric positive semi-definite: ``bias_std²·I`` on creation, then shrinking
        as motion and rests teach the bias."""
        out = np.empty((3, 3))
        _check(lib().bingham_ahrs_gyro_bias_covariance(self._h(), _ptr(out)))
        return out

    def orientation_covariance(self) -> Array:
        """The 3×3 covariance (rad²) of the orientation error as a rotation vector in the world
        frame (ENU, REP 103): ``q_true = exp(φ/2) ⊗ q̂``, what ``sensor_msgs/Imu``'s
        ``orientation_covariance`` holds (row-major there). Its trace is the square of the
        total :meth:`angular_spread`."""
        out = np.empty((3, 3))
        _check(lib().bingham_ahrs_orientation_covariance(self._h(), _ptr(out)))
        return out

    def mag_latency_estimate(self) -> Optional[float]:
        """The online estimate of the magnetometer's latency behind the gyroscope (seconds,
        0 to 40 ms in samples rounded up to an even number, 2 to 32 samples), from the IMU
        alone; ``None`` until 5 s of informative motion (a changing rotation rate with an undisturbed magnetometer)
        have been seen. Shrunk towards 0 by its own standard error (a latency the data cannot
        tell from none reads 0). A readout: pass it as ``mag_latency`` to compensate the
        latency (the default compensates this value)."""
        out = np.empty(1)
        st = lib().bingham_ahrs_mag_latency_estimate(self._h(), _ptr(out))
        if st == Status.ERR_NOT_CONVERGED:
            last_error_message()  # handled here: read, so it is not reported as unread later
            return None
        _check(st)
        return float(out[0])
