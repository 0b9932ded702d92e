"""Quaternion helpers in the library's convention: :func:`quat_multiply`, :func:`quat_conjugate`,
:func:`orientation_error` (the BROAD benchmark's error metric) and the conversions to and from
SciPy's order, :func:`to_scipy` / :func:`from_scipy`.

Conventions: quaternions are **scalar first**, ``(w, x, y, z)``, stored in the last axis of an
array (shape ``(4,)`` for one, ``(..., 4)`` for many; leading axes broadcast as in NumPy). The
product is Hamilton's (``i² = j² = k² = ijk = −1``), so ``quat_multiply(a, b)`` is the rotation
``b`` followed by ``a``: ``R(a ⊗ b) = R(a) R(b)``. The AHRS's estimate ``q``
(:meth:`bingham.Ahrs.quaternion`) maps sensor to world ENU coordinates: ``v_world = R(q) v_sensor``.

SciPy's ``Rotation.from_quat`` and ``as_quat`` use ``(x, y, z, w)`` by default (as do Eigen's
``coeffs()`` and ROS): convert with :func:`to_scipy` / :func:`from_scipy`, or, with SciPy ≥ 1.14,
pass ``scalar_first=True`` (``Rotation.from_quat(q, scalar_first=True)`` takes ours directly,
``r.as_quat(scalar_first=True)`` gives ours). Passing ours without either is a silent mistake: a
different rotation.
"""

from __future__ import annotations

from typing import NamedTuple, Union

import numpy as np

from ._arrays import Array, ArrayLike

__all__ = [
    "quat_multiply",
    "quat_conjugate",
    "OrientationError",
    "orientation_error",
    "to_scipy",
    "from_scipy",
]


def _quat(q: ArrayLike, name: str) -> Array:
    arr = np.asarray(q, dtype=np.float64)
    if arr.ndim == 0 or arr.shape[-1] != 4:
        raise ValueError(f"{name} must have shape (4,) or (..., 4), got {arr.shape}")
    return arr


def quat_multiply(a: ArrayLike, b: ArrayLike) -> Array:
    """The Hamilton product ``a ⊗ b`` of quaternions ``(w, x, y, z)`` (shape ``(4,)`` or
    ``(..., 4)``; the leading axes broadcast). As rotations: ``b`` first, then ``a``
    (``R(a ⊗ b) = R(a) R(b)``). No normalization: unit inputs give a unit result."""
    p, q = _quat(a, "a"), _quat(b, "b")
    w1, x1, y1, z1 = p[..., 0], p[..., 1], p[..., 2], p[..., 3]
    w2, x2, y2, z2 = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.stack(
        [
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ],
        axis=-1,
    )


def quat_conjugate(q: ArrayLike) -> Array:
    """The conjugate ``(w, −x, −y, −z)`` of quaternions ``(w, x, y, z)`` (shape ``(4,)`` or
    ``(..., 4)``): the inverse rotation of a unit quaternion."""
    out: Array = _quat(q, "q") * np.array([1.0, -1.0, -1.0, -1.0])
    return out


class OrientationError(NamedTuple):
    """The error of an orientation estimate in radians (see :func:`orientation_error`): floats
    for one pair of quaternions, arrays for many."""

    #: The angle of the rotation from the true to the estimated orientation, 0 to π.
    total: Union[float, Array]
    #: Its part about the world's vertical (z, up): the heading (yaw) error, 0 to π.
    heading: Union[float, Array]
    #: The rest, a rotation about a horizontal axis: the inclination (tilt) error, 0 to π.
    inclination: Union[float, Array]


def orientation_error(q: ArrayLike, truth: ArrayLike) -> OrientationError:
    """The total, heading and inclination error (radians) of the estimate ``q`` against
    ``truth``, as the BROAD benchmark (Laidig et al. 2021) defines them, for quaternions
    ``(w, x, y, z)`` mapping sensor to world coordinates with z up (the AHRS's ENU).

    With ``e = q ⊗ truth⁻¹`` normalized (the rotation, in world coordinates, from the true to
    the estimated orientation; its sign does not matter):

    * ``total = 2·acos(|e_w|)``, the angle of ``e``;
    * ``heading = 2·atan2(|e_z|, |e_w|)``, the angle of its rotation about the vertical;
    * ``inclination = 2·acos(√(e_w² + e_z²))``, the angle of the remaining rotation about a
      horizontal axis (``e`` = heading part ⊗ inclination part).

    ``q`` and ``truth`` have shape ``(4,)`` or ``(..., 4)`` (broadcast; they need not be exactly
    unit, the sign of either does not matter). Returns an :class:`OrientationError` named tuple
    ``(total, heading, inclination)``: floats for single quaternions, else arrays of the
    broadcast leading shape; NaN where an input holds NaN.
    """
    e = quat_multiply(q, quat_conjugate(truth))
    e = e / np.linalg.norm(e, axis=-1, keepdims=True)
    w, z = np.abs(e[..., 0]), np.abs(e[..., 3])
    total = 2.0 * np.arccos(np.clip(w, 0.0, 1.0))
    heading = 2.0 * np.arctan2(z, w)
    inclination = 2.0 * np.arccos(np.clip(np.sqrt(w * w + z * z), 0.0, 1.0))
    if e.ndim == 1:
        return OrientationError(float(total), float(heading), float(inclination))
    return OrientationError(total, heading, inclination)


def to_scipy(q: ArrayLike) -> Array:
    """Our ``(w, x, y, z)`` quaternions (shape ``(4,)`` or ``(..., 4)``) in SciPy's default
    order ``(x, y, z, w)`` (also Eigen's ``coeffs()`` and ROS's): for
    ``scipy.spatial.transform.Rotation.from_quat(to_scipy(q))``. With SciPy ≥ 1.14,
    ``Rotation.from_quat(q, scalar_first=True)`` takes ``q`` directly."""
    return np.roll(_quat(q, "q"), -1, axis=-1)


def from_scipy(xyzw: ArrayLike) -> Array:
    """Quaternions in SciPy's default order ``(x, y, z, w)`` (``Rotation.as_quat()``, Eigen's
    ``coeffs()``, ROS) as ours, ``(w, x, y, z)``; shape ``(4,)`` or ``(..., 4)``. With SciPy ≥
    1.14, ``r.as_quat(scalar_first=True)`` gives ours directly."""
    return np.roll(_quat(xyzw, "xyzw"), 1, axis=-1)
