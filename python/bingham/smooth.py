"""The offline smoother (``bingham_ahrs_smooth_ex``): the orientation at every sample of a whole
recording from the samples before and after it, with its uncertainty. See docs/guide.md,
"Recorded logs: the smoother"; the command line is ``python -m bingham smooth``."""

from __future__ import annotations

import ctypes
from typing import NamedTuple, Optional, Tuple, Union

import numpy as np

from ._arrays import Array, ArrayLike, _in, _ptr
from .ahrs import AhrsParams, _known_fields, _refuse_rate, _rows3
from .errors import _check
from ._library import lib

__all__ = ["smooth", "Smoothed", "BYTES_PER_SAMPLE", "BIAS_BYTES_PER_SAMPLE"]

#: The bytes the smoother allocates per sample (``bingham_ahrs_smooth``).
BYTES_PER_SAMPLE = 112
#: The further bytes per sample with the bias output (``full=True``).
BIAS_BYTES_PER_SAMPLE = 72


class Smoothed(NamedTuple):
    """What :func:`smooth` returns with ``full=True``: ``quat`` (n×4, w, x, y, z, sensor → world
    ENU, w ≥ 0), ``spread`` (n, rad: the total angular standard deviation), ``bias`` (n×3,
    rad/s: the smoothed gyroscope bias) and ``covariance`` (n×3×3, rad²: the orientation
    error's covariance as a rotation vector in the world frame)."""

    quat: Array
    spread: Array
    bias: Array
    covariance: Array


def smooth(
    gyr: ArrayLike,
    acc: ArrayLike,
    mag: Optional[ArrayLike] = None,
    sample_time: float = 0.01,
    time: Optional[ArrayLike] = None,
    params: Optional[AhrsParams] = None,
    full: bool = False,
    **overrides: float,
) -> Union[Tuple[Array, Array], Smoothed]:
    """Smooths a whole recording: ``gyr`` (rad/s), ``acc`` (m/s²) and ``mag`` (any unit, or
    None) n×3 arrays, sampled every ``sample_time`` seconds (the period, not the rate), or at
    the timestamps ``time`` (n values, seconds, strictly increasing). A row holding NaN means
    "no sample" of that sensor at that time. ``params`` (an :class:`AhrsParams` whose
    ``sample_time`` is used) and keyword overrides (``acc_noise=…``) as for :class:`Ahrs`.

    Returns ``(quat, spread)`` — the n×4 smoothed quaternions and the n total angular spreads
    (rad) — or, with ``full=True``, a :class:`Smoothed` with the bias and the covariances too.
    Raises :class:`BinghamError` (nothing returned) for a recording the AHRS refuses (a first
    sample without gravity, a gyroscope row turning more than 1e6 rad, timestamps not
    increasing; the message names the sample) and :class:`ValueError` for wrong shapes. Memory:
    :data:`BYTES_PER_SAMPLE` bytes per sample besides the arrays (:data:`BIAS_BYTES_PER_SAMPLE`
    more with ``full=True``). Runs the backward pass on a second thread on recordings of more
    than a minute (the result does not depend on it; ``bingham_ahrs_smooth``'s threads)."""
    if params is None:
        sample_time = float(sample_time)
        _refuse_rate(sample_time, "smooth")
        p = AhrsParams.default(sample_time)
    else:
        if not isinstance(params, AhrsParams):
            raise TypeError(f"params must be an AhrsParams, got {type(params).__name__}")
        p = params.copy()
    _known_fields(overrides)
    for k, v in overrides.items():
        setattr(p, k, float(v))
    g = _rows3(gyr, "gyr")
    n = g.shape[0]
    a = _rows3(acc, "acc", n)
    m = None if mag is None else _rows3(mag, "mag", n)
    t = None if time is None else _in(time, "time", (n,))
    q = np.empty((n, 4))
    s = np.empty(n)
    b = np.empty((n, 3)) if full else None
    c = np.empty((n, 3, 3)) if full else None
    _check(
        lib().bingham_ahrs_smooth_ex(
            ctypes.byref(p), n, _ptr(t), _ptr(g), _ptr(a), _ptr(m), _ptr(q), _ptr(s), _ptr(b), _ptr(c)
        )
    )
    if full:
        assert b is not None and c is not None
        return Smoothed(q, s, b, c)
    return q, s
