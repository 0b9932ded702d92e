"""Array arguments: the ``ArrayLike`` / ``Array`` types, and the conversion of array-likes to
C-contiguous ``float64`` arrays with the shape checks the C side relies on (it trusts lengths)."""

from __future__ import annotations

from typing import Any, Optional, Tuple

import numpy as np
import numpy.typing as npt

from ._library import _D

ArrayLike = npt.ArrayLike
#: The type of every array returned: a NumPy array of ``float64``.
Array = npt.NDArray[np.float64]


def _in(a: ArrayLike, name: str, shape: Optional[Tuple[int, ...]] = None) -> Array:
    """A C-contiguous float64 copy-or-view of `a`, shape-checked (the C side trusts lengths)."""
    arr = np.ascontiguousarray(a, dtype=np.float64)
    if shape is not None and arr.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {arr.shape}")
    return arr


def _ptr(arr: Optional[Array]) -> Any:
    return None if arr is None else arr.ctypes.data_as(_D)


def _vec(z: ArrayLike, name: str = "z") -> Tuple[int, Array]:
    z = _in(z, name)
    if z.ndim != 1:
        raise ValueError(f"{name} must be a vector, got shape {z.shape}")
    return z.shape[0], z


def _dist(m: ArrayLike, z: ArrayLike, names: Tuple[str, str] = ("m", "z")) -> Tuple[int, Array, Array]:
    d, z = _vec(z, names[1])
    return d, _in(m, names[0], (d, d)), z


def _points(x: ArrayLike, d: int) -> Tuple[Array, bool]:
    x = _in(x, "x")
    single = x.ndim == 1
    x2 = x.reshape(1, -1) if single else x
    if x2.ndim != 2 or x2.shape[1] != d:
        raise ValueError(f"x must have shape (n, {d}) or ({d},), got {x.shape}")
    return np.ascontiguousarray(x2), single
