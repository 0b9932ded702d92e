"""bingham: Bingham distributions on spheres, the recursive Bingham filter and the Bingham AHRS.

The Python binding of the ``bingham`` Rust library, through its C ABI (``include/bingham.h``) and
``ctypes``: the package ships the compiled library (``bingham/_lib/libbingham*.so``, built by
``pip install ./python`` from the repository). Every function of the header is bound with its
argument and result types (``lib()`` returns the configured ``ctypes.CDLL``); the Python functions
below take any array-like (lists, NumPy arrays) and return NumPy ``float64`` arrays, and raise
:class:`BinghamError` (with the library's status and message) on any status other than
``BINGHAM_OK``; a wrongly shaped argument raises :class:`ValueError` before the library is called.

Conventions (the same as in C and Rust):

* ``f(x) = exp(xᵀ M Z Mᵀ x) / F(Z)`` on the unit sphere S^{d-1}, F with respect to the surface
  measure (F(0) = 2π, 4π, 2π² for d = 2, 3, 4); d = 2..64.
* ``m``: d×d orthogonal, columns are the principal directions, the last column is the mode.
* ``z``: length d, any order and shift on input; outputs sorted ascending with ``z[-1] == 0``.
* Quaternions are scalar first ``(w, x, y, z)``; complex numbers are ``(re, im)``. (Eigen's
  ``coeffs()``, ROS and SciPy's ``as_quat()`` are ``(x, y, z, w)``: reorder with
  ``np.roll(q, 1)``.)

Which library is loaded (:func:`library_path` tells): the file named by the environment variable
``BINGHAM_LIB`` if set (for developers: a freshly built ``target/release/libbingham.so``), else the
one bundled in the package, else ``target/release`` or ``target/debug`` of the checkout when the
package is used from the source tree, else the system's (``libbingham.so.0`` of ``make install``).

Thread safety: the library is thread-safe; the error message read by :class:`BinghamError` is
per thread, so exceptions carry the message of their own call.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import enum
import glob
import os
import re
from typing import Any, Callable, Dict, Iterator, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

ArrayLike = npt.ArrayLike
#: The type of every array returned: a NumPy array of ``float64``.
Array = npt.NDArray[np.float64]

__all__ = [
    "__version__",
    "Array",
    "BinghamError",
    "Status",
    "MIN_DIM",
    "MAX_DIM",
    "ORTHOGONALITY_TOL",
    "UNIT_TOL",
    "lib",
    "library_path",
    "version",
    "status_str",
    "last_error_message",
    "normalization_constant",
    "log_normalization_constant",
    "log_normalization_constant_saddlepoint",
    "log_normalization_hessian",
    "second_moment",
    "mle",
    "mle_samples",
    "multiply",
    "compose",
    "pdf",
    "log_pdf",
    "entropy",
    "kl_divergence",
    "sample",
    "rotate_left",
    "rotate_right",
    "mode",
    "deterministic_samples",
    "Filter",
    "vector_observation",
    "noise_from_angle_std",
    "angular_spread",
    "AhrsParams",
    "Ahrs",
]

MIN_DIM = 2
MAX_DIM = 64
ORTHOGONALITY_TOL = 1e-6
UNIT_TOL = 1e-6


class Status(enum.IntEnum):
    """The values of ``bingham_status`` (stable; new codes are only appended)."""

    OK = 0
    ERR_NULL_ARGUMENT = 1
    ERR_INVALID_DIMENSION = 2
    ERR_INVALID_ARGUMENT = 3
    ERR_NOT_CONVERGED = 4
    ERR_NUMERICAL = 5
    ERR_PANIC = 6
    ERR_CALLBACK = 7


class BinghamError(Exception):
    """A call returned a status other than ``BINGHAM_OK``.

    Attributes: ``status`` (int, a :class:`Status` value when known), ``status_name`` (the
    library's ``bingham_status_str``) and ``message`` (the library's last error message).
    """

    def __init__(self, status: int, message: str) -> None:
        self.status: Union[Status, int] = Status(status) if status in Status._value2member_map_ else status
        self.status_name = status_str(status)
        self.message = message
        super().__init__(f"{self.status_name} ({int(status)}): {message}")


_D = ctypes.POINTER(ctypes.c_double)
_SIZE = ctypes.c_size_t
_STATUS = ctypes.c_int

#: ``bingham_transition_fn``: ``int fn(const double *x_in, double *x_out, void *user_data)``.
_TRANSITION_FN = ctypes.CFUNCTYPE(ctypes.c_int, _D, _D, ctypes.c_void_p)
#: ``bingham_log_likelihood_fn``: ``int fn(const double *x, double *log_l, void *user_data)``.
_LOG_LIKELIHOOD_FN = ctypes.CFUNCTYPE(ctypes.c_int, _D, _D, ctypes.c_void_p)

# name -> (restype, argtypes), in the order of the header.
_SIGNATURES = {
    "bingham_version": (ctypes.c_char_p, []),
    "bingham_status_str": (ctypes.c_char_p, [ctypes.c_int]),
    "bingham_last_error_message": (
        _STATUS,
        [ctypes.c_char_p, _SIZE, ctypes.POINTER(_SIZE)],
    ),
    "bingham_normalization_constant": (_STATUS, [_SIZE, _D, _D, _D]),
    "bingham_log_normalization_constant": (_STATUS, [_SIZE, _D, _D, _D]),
    "bingham_log_normalization_constant_saddlepoint": (_STATUS, [_SIZE, _D, _D, _D]),
    "bingham_log_normalization_hessian": (_STATUS, [_SIZE, _D, _D, _D, _D]),
    "bingham_second_moment": (_STATUS, [_SIZE, _D, _D, _D]),
    "bingham_mle": (_STATUS, [_SIZE, _D, _D, _D]),
    "bingham_mle_samples": (_STATUS, [_SIZE, _SIZE, _D, _D, _D, _D]),
    "bingham_multiply": (_STATUS, [_SIZE, _D, _D, _D, _D, _D, _D]),
    "bingham_compose": (_STATUS, [_SIZE, _D, _D, _D, _D, _D, _D]),
    "bingham_pdf": (_STATUS, [_SIZE, _D, _D, _SIZE, _D, _D]),
    "bingham_log_pdf": (_STATUS, [_SIZE, _D, _D, _SIZE, _D, _D]),
    "bingham_entropy": (_STATUS, [_SIZE, _D, _D, _D]),
    "bingham_kl_divergence": (_STATUS, [_SIZE, _D, _D, _D, _D, _D]),
    "bingham_sample": (_STATUS, [_SIZE, _D, _D, ctypes.c_uint64, _SIZE, _D]),
    "bingham_rotate_left": (_STATUS, [_SIZE, _D, _D, _D, _D, _D]),
    "bingham_rotate_right": (_STATUS, [_SIZE, _D, _D, _D, _D, _D]),
    "bingham_mode": (_STATUS, [_SIZE, _D, _D, _D]),
    "bingham_deterministic_sample_count": (_STATUS, [_SIZE, ctypes.c_int, ctypes.POINTER(_SIZE)]),
    "bingham_deterministic_samples": (
        _STATUS,
        [
            _SIZE, _D, _D, ctypes.c_int, ctypes.c_double, _SIZE, _D, _D,
            ctypes.POINTER(_SIZE), ctypes.POINTER(ctypes.c_int),
        ],
    ),
    "bingham_filter_new": (_STATUS, [_SIZE, _D, _D, ctypes.POINTER(ctypes.c_void_p)]),
    "bingham_filter_free": (None, [ctypes.c_void_p]),
    "bingham_filter_clone": (_STATUS, [ctypes.c_void_p, ctypes.POINTER(ctypes.c_void_p)]),
    "bingham_filter_dim": (_STATUS, [ctypes.c_void_p, ctypes.POINTER(_SIZE)]),
    "bingham_filter_set_state": (_STATUS, [ctypes.c_void_p, _D, _D]),
    "bingham_filter_get_state": (_STATUS, [ctypes.c_void_p, _D, _D]),
    "bingham_filter_mode": (_STATUS, [ctypes.c_void_p, _D]),
    "bingham_filter_predict": (_STATUS, [ctypes.c_void_p, _D, _D]),
    "bingham_filter_predict_rotation": (_STATUS, [ctypes.c_void_p, _D, _D, _D]),
    "bingham_filter_update": (_STATUS, [ctypes.c_void_p, _D, _D, _D]),
    "bingham_filter_log_likelihood": (_STATUS, [ctypes.c_void_p, _D, _D, _D, _D]),
    "bingham_filter_update_vector": (_STATUS, [ctypes.c_void_p, _D, _D, ctypes.c_double]),
    "bingham_filter_log_likelihood_vector": (
        _STATUS,
        [ctypes.c_void_p, _D, _D, ctypes.c_double, _D],
    ),
    "bingham_filter_predict_nonlinear": (_STATUS, [ctypes.c_void_p, _TRANSITION_FN, ctypes.c_void_p, _D, _D]),
    "bingham_filter_update_nonlinear": (_STATUS, [ctypes.c_void_p, _LOG_LIKELIHOOD_FN, ctypes.c_void_p]),
    "bingham_filter_angular_spread": (_STATUS, [ctypes.c_void_p, _D]),
    "bingham_vector_observation": (_STATUS, [_D, _D, ctypes.c_double, _D, _D]),
    "bingham_noise_from_angle_std": (_STATUS, [_SIZE, ctypes.c_double, _D, _D]),
    "bingham_angular_spread": (_STATUS, [_SIZE, _D, _D, _D]),
    "bingham_ahrs_params_default": (_STATUS, [ctypes.c_double, ctypes.c_void_p]),
    "bingham_ahrs_new": (_STATUS, [ctypes.c_void_p, ctypes.POINTER(ctypes.c_void_p)]),
    "bingham_ahrs_free": (None, [ctypes.c_void_p]),
    "bingham_ahrs_clone": (_STATUS, [ctypes.c_void_p, ctypes.POINTER(ctypes.c_void_p)]),
    "bingham_ahrs_update": (_STATUS, [ctypes.c_void_p, _D, _D, _D]),
    "bingham_ahrs_update_batch": (_STATUS, [ctypes.c_void_p, _SIZE, _D, _D, _D, _D]),
    "bingham_ahrs_update_batch_spread": (_STATUS, [ctypes.c_void_p, _SIZE, _D, _D, _D, _D, _D]),
    "bingham_ahrs_quaternion": (_STATUS, [ctypes.c_void_p, _D]),
    "bingham_ahrs_state": (_STATUS, [ctypes.c_void_p, _D, _D]),
    "bingham_ahrs_set_state": (_STATUS, [ctypes.c_void_p, _D, _D]),
    "bingham_ahrs_angular_spread": (_STATUS, [ctypes.c_void_p, _D]),
    "bingham_ahrs_gyro_bias": (_STATUS, [ctypes.c_void_p, _D]),
}


_HERE = os.path.dirname(os.path.abspath(__file__))


def _bundled() -> Optional[str]:
    """The library shipped in the package (``_lib/libbingham.abi3.so`` or similar), if any."""
    found = sorted(glob.glob(os.path.join(_HERE, "_lib", "libbingham*.so")))
    return found[0] if found else None


def _candidates() -> Iterator[str]:
    env = os.environ.get("BINGHAM_LIB")
    if env:
        yield env
        return
    bundled = _bundled()
    if bundled:
        yield bundled
        return
    for profile in ("release", "debug"):  # used from the checkout (python/bingham/)
        yield os.path.join(_HERE, "..", "..", "target", profile, "libbingham.so")
    found = ctypes.util.find_library("bingham")
    if found:
        yield found
    yield "libbingham.so.0"


def _load() -> Tuple[ctypes.CDLL, str]:
    errors = []
    for path in _candidates():
        if os.sep in path and not os.path.exists(path):
            errors.append(f"{path}: not found")
            continue
        try:
            cdll = ctypes.CDLL(path)
        except OSError as e:
            errors.append(f"{path}: {e}")
            continue
        for name, (restype, argtypes) in _SIGNATURES.items():
            try:
                fn = getattr(cdll, name)
            except AttributeError:  # an older library without this function
                continue
            fn.restype = restype
            fn.argtypes = argtypes
        return cdll, (os.path.abspath(path) if os.sep in path else path)
    raise OSError(
        "cannot load libbingham (install the package with `pip install ./python` from the "
        "repository, or set BINGHAM_LIB to a libbingham.so): " + "; ".join(errors)
    )


_LIB: Optional[ctypes.CDLL] = None
_LIB_PATH: Optional[str] = None


def lib() -> ctypes.CDLL:
    """The loaded ``ctypes.CDLL`` with ``argtypes``/``restype`` set for every function."""
    global _LIB, _LIB_PATH
    if _LIB is None:
        _LIB, _LIB_PATH = _load()
    return _LIB


def library_path() -> str:
    """The path (or the name given to the dynamic loader) of the loaded library."""
    lib()
    assert _LIB_PATH is not None
    return _LIB_PATH


def _package_version() -> str:
    # used from the checkout (python/bingham/, e.g. with BINGHAM_LIB): the crate's version
    cargo_toml = os.path.join(_HERE, "..", "..", "Cargo.toml")
    if os.path.isfile(os.path.join(_HERE, "..", "setup.py")) and os.path.isfile(cargo_toml):
        with open(cargo_toml, encoding="utf-8") as f:
            found = re.search(r'^version\s*=\s*"([^"]+)"', f.read(), re.M)
        if found:
            return found.group(1)
    try:
        from importlib.metadata import PackageNotFoundError, version as dist_version
    except ImportError:  # pragma: no cover
        return "unknown"
    try:
        return dist_version("bingham")
    except PackageNotFoundError:  # pragma: no cover
        return "unknown"


#: The package's version: the crate's (``Cargo.toml``), set when the package is built; the
#: bundled library's :func:`version` is the same.
__version__: str = _package_version()


# ---- helpers ---------------------------------------------------------------------------------


def _in(a: ArrayLike, name: str, shape: Optional[Tuple[int, ...]] = None) -> Array:
    """A C-contiguous float64 copy-or-view of `a`, shape-checked (the C side trusts lengths)."""
    arr = np.ascontiguousarray(a, dtype=np.float64)
    if shape is not None and arr.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {arr.shape}")
    return arr


def _ptr(arr: Optional[Array]) -> Any:
    return None if arr is None else arr.ctypes.data_as(_D)


def _check(status: int) -> None:
    if status != Status.OK:
        raise BinghamError(status, last_error_message())


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


# ---- the API ---------------------------------------------------------------------------------


def version() -> str:
    """The library version string, e.g. ``"0.1.0"``."""
    return str(lib().bingham_version().decode())


def status_str(status: int) -> str:
    """The library's static description of a status code (any int)."""
    return str(lib().bingham_status_str(int(status)).decode())


def last_error_message() -> str:
    """This thread's last error message ('' if no call failed yet)."""
    n = _SIZE(0)
    _check_raw(lib().bingham_last_error_message(None, 0, ctypes.byref(n)))
    buf = ctypes.create_string_buffer(n.value + 1)
    _check_raw(lib().bingham_last_error_message(buf, len(buf), ctypes.byref(n)))
    return buf.value.decode("utf-8", errors="replace")


def _check_raw(status: int) -> None:
    if status != Status.OK:  # only possible on misuse; do not recurse into last_error_message
        raise BinghamError(status, "bingham_last_error_message failed")


def normalization_constant(z: ArrayLike) -> Tuple[float, Array]:
    """``(F, dF/dz)`` for concentrations ``z`` (any order/shift); F with the surface measure.

    Raises BinghamError (ERR_NUMERICAL) when F overflows a double: use the log version.
    """
    d, z = _vec(z)
    f = np.empty(1)
    df = np.empty(d)
    _check(lib().bingham_normalization_constant(d, _ptr(z), _ptr(f), _ptr(df)))
    return float(f[0]), df


def _log_norm(fn: Any, z: ArrayLike) -> Tuple[float, Array]:
    d, z = _vec(z)
    lf = np.empty(1)
    g = np.empty(d)
    _check(fn(d, _ptr(z), _ptr(lf), _ptr(g)))
    return float(lf[0]), g


def log_normalization_constant(z: ArrayLike) -> Tuple[float, Array]:
    """``(log F, d log F/dz)``; the gradient is E[x_i²] in the principal frame (sums to 1)."""
    return _log_norm(lib().bingham_log_normalization_constant, z)


def log_normalization_constant_saddlepoint(z: ArrayLike) -> Tuple[float, Array]:
    """APPROXIMATE ``(log F, d log F/dz)`` by the saddlepoint method (errors up to several %)."""
    return _log_norm(lib().bingham_log_normalization_constant_saddlepoint, z)


def log_normalization_hessian(z: ArrayLike) -> Tuple[float, Array, Array]:
    """``(log F, gradient, Hessian)`` of log F, in the order of the input ``z``."""
    d, z = _vec(z)
    lf = np.empty(1)
    g = np.empty(d)
    h = np.empty((d, d))
    _check(lib().bingham_log_normalization_hessian(d, _ptr(z), _ptr(lf), _ptr(g), _ptr(h)))
    return float(lf[0]), g, h


def second_moment(m: ArrayLike, z: ArrayLike) -> Array:
    """``S = E[x xᵀ]`` (d×d, trace 1) of Bingham(m, z)."""
    d, m, z = _dist(m, z)
    s = np.empty((d, d))
    _check(lib().bingham_second_moment(d, _ptr(m), _ptr(z), _ptr(s)))
    return s


def mle(s: ArrayLike) -> Tuple[Array, Array]:
    """Moment-matching / maximum-likelihood ``(m, z)`` for a second-moment matrix ``s``."""
    s = _in(s, "s")
    if s.ndim != 2 or s.shape[0] != s.shape[1]:
        raise ValueError(f"s must be square, got shape {s.shape}")
    d = s.shape[0]
    m = np.empty((d, d))
    z = np.empty(d)
    _check(lib().bingham_mle(d, _ptr(s), _ptr(m), _ptr(z)))
    return m, z


def mle_samples(x: ArrayLike, w: Optional[ArrayLike] = None) -> Tuple[Array, Array]:
    """Maximum-likelihood ``(m, z)`` for unit vectors ``x`` (n×d), optional weights ``w`` (n)."""
    x = _in(x, "x")
    if x.ndim != 2:
        raise ValueError(f"x must have shape (n, d), got {x.shape}")
    n, d = x.shape
    if w is not None:
        w = _in(w, "w", (n,))
    m = np.empty((d, d))
    z = np.empty(d)
    _check(lib().bingham_mle_samples(d, n, _ptr(x), _ptr(w), _ptr(m), _ptr(z)))
    return m, z


def _binary(fn: Any, m1: ArrayLike, z1: ArrayLike, m2: ArrayLike, z2: ArrayLike) -> Tuple[Array, Array]:
    d, m1, z1 = _dist(m1, z1, ("m1", "z1"))
    m2 = _in(m2, "m2", (d, d))
    z2 = _in(z2, "z2", (d,))
    m = np.empty((d, d))
    z = np.empty(d)
    _check(fn(d, _ptr(m1), _ptr(z1), _ptr(m2), _ptr(z2), _ptr(m), _ptr(z)))
    return m, z


def multiply(m1: ArrayLike, z1: ArrayLike, m2: ArrayLike, z2: ArrayLike) -> Tuple[Array, Array]:
    """Product of two Bingham densities (Bayes update), ``(m, z)``; exact."""
    return _binary(lib().bingham_multiply, m1, z1, m2, z2)


def compose(m1: ArrayLike, z1: ArrayLike, m2: ArrayLike, z2: ArrayLike) -> Tuple[Array, Array]:
    """Moment-matched distribution of ``x ⊕ y`` (d = 2: complex, d = 4: quaternion product)."""
    return _binary(lib().bingham_compose, m1, z1, m2, z2)


def _pointwise(fn: Any, m: ArrayLike, z: ArrayLike, x: ArrayLike) -> Union[float, Array]:
    d, m, z = _dist(m, z)
    x, single = _points(x, d)
    n = x.shape[0]
    p = np.empty(n)
    _check(fn(d, _ptr(m), _ptr(z), n, _ptr(x), _ptr(p)))
    return float(p[0]) if single else p


def pdf(m: ArrayLike, z: ArrayLike, x: ArrayLike) -> Union[float, Array]:
    """Density at unit vector(s) ``x`` ((d,) → float, (n, d) → array), surface measure."""
    return _pointwise(lib().bingham_pdf, m, z, x)


def log_pdf(m: ArrayLike, z: ArrayLike, x: ArrayLike) -> Union[float, Array]:
    """Log density at unit vector(s) ``x``."""
    return _pointwise(lib().bingham_log_pdf, m, z, x)


def entropy(m: ArrayLike, z: ArrayLike) -> float:
    """Differential entropy in nats (w.r.t. the surface measure)."""
    d, m, z = _dist(m, z)
    h = np.empty(1)
    _check(lib().bingham_entropy(d, _ptr(m), _ptr(z), _ptr(h)))
    return float(h[0])


def kl_divergence(m1: ArrayLike, z1: ArrayLike, m2: ArrayLike, z2: ArrayLike) -> float:
    """``KL(p1 ‖ p2)`` in nats."""
    d, m1, z1 = _dist(m1, z1, ("m1", "z1"))
    m2 = _in(m2, "m2", (d, d))
    z2 = _in(z2, "z2", (d,))
    kl = np.empty(1)
    _check(lib().bingham_kl_divergence(d, _ptr(m1), _ptr(z1), _ptr(m2), _ptr(z2), _ptr(kl)))
    return float(kl[0])


def sample(m: ArrayLike, z: ArrayLike, n: int, seed: int = 0) -> Array:
    """``n`` samples (n×d unit vectors); deterministic in ``seed`` for a given library version."""
    d, m, z = _dist(m, z)
    n = int(n)
    if n < 0:
        raise ValueError("n must be >= 0")
    x = np.empty((n, d))
    _check(lib().bingham_sample(d, _ptr(m), _ptr(z), int(seed) & (2**64 - 1), n, _ptr(x)))
    return x


def _rotate(fn: Any, m: ArrayLike, z: ArrayLike, u: ArrayLike) -> Tuple[Array, Array]:
    d, m, z = _dist(m, z)
    u = _in(u, "u", (d,))
    mo = np.empty((d, d))
    zo = np.empty(d)
    _check(fn(d, _ptr(m), _ptr(z), _ptr(u), _ptr(mo), _ptr(zo)))
    return mo, zo


def rotate_left(m: ArrayLike, z: ArrayLike, u: ArrayLike) -> Tuple[Array, Array]:
    """Distribution of ``u ⊕ x`` for a fixed unit ``u`` (d = 2, 4), ``(m, z)``."""
    return _rotate(lib().bingham_rotate_left, m, z, u)


def rotate_right(m: ArrayLike, z: ArrayLike, u: ArrayLike) -> Tuple[Array, Array]:
    """Distribution of ``x ⊕ u`` for a fixed unit ``u`` (d = 2, 4), ``(m, z)``."""
    return _rotate(lib().bingham_rotate_right, m, z, u)


def mode(m: ArrayLike, z: ArrayLike) -> Array:
    """The mode (a unit vector; ``-mode`` is equally a mode)."""
    d, m, z = _dist(m, z)
    out = np.empty(d)
    _check(lib().bingham_mode(d, _ptr(m), _ptr(z), _ptr(out)))
    return out


#: The deterministic sampling schemes (``BINGHAM_SAMPLES_*``) by name.
_SCHEMES = {"tac2016": 0, "moments": 1}


def deterministic_samples(
    m: ArrayLike, z: ArrayLike, scheme: str = "moments", lam: float = 0.5
) -> Tuple[Array, Array, int]:
    """Deterministic samples of Bingham(m, z): ``(points, weights, reproduced)``.

    ``points`` is n×d (unit vectors, each in the mode's hemisphere), ``weights`` has length n
    (positive, summing to 1), and ``reproduced`` says what the weighted points reproduce
    exactly: 2 (the second moment ``E[x xᵀ]``) or 4 (the second and every fourth moment).

    * ``scheme="moments"``: ``2d² − 4d + 3`` points (3, 9, 19 for d = 2, 3, 4) reproducing every
      second and fourth moment (``reproduced == 4``); where no positive point set of that kind
      exists (about 5 % of random z for d = 4: a very broad axis next to a moderately sharp
      one) the ``2d − 1`` points of ``"tac2016"`` with ``lam = 0.5`` instead
      (``reproduced == 2``). ``lam`` is ignored.
    * ``scheme="tac2016"``: the ``2d − 1`` points of Gilitschenski et al. (IEEE TAC 2016) with
      the weighting parameter ``lam`` in ``[0, 1]`` (the mode gets the weight ``lam · ω_mode``,
      ω_mode = E[(mode·x)²]; libDirectional's default is 0.5); they reproduce the second
      moment (``reproduced == 2``).
    """
    d, m, z = _dist(m, z)
    try:
        code = _SCHEMES[scheme]
    except KeyError:
        raise ValueError(f"scheme must be one of {sorted(_SCHEMES)}, got {scheme!r}") from None
    cap = _SIZE(0)
    _check(lib().bingham_deterministic_sample_count(d, code, ctypes.byref(cap)))
    points = np.empty((cap.value, d))
    weights = np.empty(cap.value)
    n = _SIZE(0)
    reproduced = ctypes.c_int(0)
    _check(
        lib().bingham_deterministic_samples(
            d, _ptr(m), _ptr(z), code, float(lam), cap.value, _ptr(points), _ptr(weights),
            ctypes.byref(n), ctypes.byref(reproduced),
        )
    )
    return points[: n.value].copy(), weights[: n.value].copy(), int(reproduced.value)


class _Callback:
    """Runs a Python callable for the library without letting an exception cross into C.

    The first exception raised by the callable (or by checking its result) is stored and the
    callback returns 1 (failure); the library then stops and returns ``BINGHAM_ERR_CALLBACK``
    with the filter unchanged, and :meth:`check` raises :class:`BinghamError` from the stored
    exception (``KeyboardInterrupt`` and other non-``Exception`` exceptions are re-raised as
    they are).
    """

    def __init__(self) -> None:
        self.error: Optional[BaseException] = None

    def run(self, body: Callable[[], None]) -> int:
        if self.error is not None:  # the library stops at the first failure; be safe anyway
            return 1
        try:
            body()
        except BaseException as e:  # nothing may unwind into C
            self.error = e
            return 1
        return 0

    def check(self, status: int) -> None:
        err = self.error
        if err is not None and not isinstance(err, Exception):
            raise err
        if status != Status.OK:
            exc = BinghamError(status, last_error_message())
            if err is not None:
                raise exc from err
            raise exc


class Filter:
    """The recursive Bingham filter (d = 2: axes as ``(re, im)``; d = 4: unit quaternions,
    scalar first), owning a ``bingham_filter`` handle.

    System ``x[k+1] = x[k] ⊕ w[k]``, measurement ``z[k] = x[k] ⊕ v[k]`` with Bingham noises
    given as ``(m, z)`` pairs; nonlinear models ``x[k+1] = a(x[k]) ⊕ w[k]`` and any likelihood
    through Python callables (:meth:`predict_nonlinear`, :meth:`update_nonlinear`). A failed
    call raises :class:`BinghamError` and leaves the filter unchanged. Use one filter per
    thread at a time; :meth:`clone` gives an independent copy.
    The handle is released by :meth:`close`, by leaving a ``with`` block, or when the object
    is garbage collected.
    """

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
        if self._handle is None:
            raise ValueError("the filter has been closed")
        if self._busy:
            raise ValueError("the filter is in a nonlinear step: its callback must not use it")
        return self._handle

    def close(self) -> None:
        """Releases the handle (idempotent)."""
        if getattr(self, "_busy", False):
            raise ValueError("the filter is in a nonlinear step: its callback must not close it")
        if getattr(self, "_handle", None) is not None:
            lib().bingham_filter_free(self._handle)
            self._handle = None

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # interpreter shutdown: the library may be gone already
            pass

    def __enter__(self) -> "Filter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

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
        self, fn: Callable[[Array], ArrayLike], m_w: ArrayLike, z_w: ArrayLike
    ) -> None:
        """Nonlinear prediction ``x[k+1] = fn(x[k]) ⊕ w[k]``, w ~ Bingham(m_w, z_w).

        ``fn`` is called once per deterministic sample of the state (19 for d = 4, 3 for d = 2;
        fewer where the scheme falls back, see :func:`deterministic_samples`) with a unit vector
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
            status = lib().bingham_filter_predict_nonlinear(handle, cb, None, _ptr(m_w), _ptr(z_w))
        finally:
            self._busy = False
        guard.check(status)

    def update_nonlinear(self, log_likelihood: Callable[[Array], float]) -> None:
        """Nonlinear Bayes update: posterior ∝ prior(x) · L(x), ``log_likelihood(x)`` = log L(x).

        ``log_likelihood`` gets a unit vector ``x`` (a NumPy array of length d, a copy) and
        returns a finite float; ``L(-x) = L(x)`` is the caller's contract. The update is
        progressive (tempered): a Bingham exponent is fitted to ``log L`` at the deterministic
        samples of the current approximation (19 calls per round for d = 4, 5 for d = 2) and
        multiplied in as ``exp(Δβ xᵀPx)``, with ``Δβ`` such that the part of ``log L`` the fit
        misses contributes at most ``TEMPERING_RESIDUAL = 1`` per step (a Bingham likelihood is
        absorbed exactly, in one step), then two importance-weighted moment matches correct the
        result (at most 200 steps; beyond that ``ERR_NOT_CONVERGED``). Reliable where the
        posterior is close to a Bingham distribution (one mode up to the sign); for a Bingham
        likelihood :meth:`update` and :func:`multiply` are exact.

        ``log_likelihood`` must not use this filter. If it raises or returns a non-finite value,
        the filter is unchanged and :class:`BinghamError` with status ``ERR_CALLBACK`` is raised
        (``from`` the callable's exception, if any).
        """
        d = self.d
        guard = _Callback()

        def call(x_in: Any, log_l: Any) -> None:
            x = np.ctypeslib.as_array(x_in, shape=(d,)).copy()
            log_l[0] = float(log_likelihood(x))

        cb = _LOG_LIKELIHOOD_FN(lambda x_in, log_l, _user: guard.run(lambda: call(x_in, log_l)))
        handle = self._h()
        self._busy = True
        try:
            status = lib().bingham_filter_update_nonlinear(handle, cb, None)
        finally:
            self._busy = False
        guard.check(status)

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


# ---- vector observations and the AHRS ---------------------------------------------------------


def vector_observation(body: ArrayLike, reference: ArrayLike, kappa: float) -> Tuple[Array, Array]:
    """The likelihood ``exp(kappa rᵀ R(q) b)`` of a measured direction ``body`` (sensor frame)
    of the known ``reference`` (world frame) as a Bingham distribution of the quaternion q
    (scalar first, sensor → world): ``(m, z)``, z = (−2κ, −2κ, 0, 0)."""
    b = _in(body, "body", (3,))
    r = _in(reference, "reference", (3,))
    m = np.empty((4, 4))
    z = np.empty(4)
    _check(lib().bingham_vector_observation(_ptr(b), _ptr(r), float(kappa), _ptr(m), _ptr(z)))
    return m, z


def noise_from_angle_std(d: int, sigma: float) -> Tuple[Array, Array]:
    """Isotropic rotation noise with angular standard deviation ``sigma`` (radians) as
    ``(m, z)`` with the mode at the identity (d = 4: Gaussian rotation vector; d = 2: Gaussian
    angle), the exact moment-matched Bingham."""
    m = np.empty((d, d))
    z = np.empty(d)
    _check(lib().bingham_noise_from_angle_std(d, float(sigma), _ptr(m), _ptr(z)))
    return m, z


def angular_spread(m: ArrayLike, z: ArrayLike) -> Array:
    """Angular spread in radians (d = 2, 4): entries 0..d-2 along the principal directions
    (columns of m), entry d-1 the total (d = 4: RMS of 2 sin(θ/2), θ the rotation angle from the
    mode, ≈ the RMS angle)."""
    d, m, z = _dist(m, z)
    out = np.empty(d)
    _check(lib().bingham_angular_spread(d, _ptr(m), _ptr(z), _ptr(out)))
    return out


class AhrsParams(ctypes.Structure):
    """``bingham_ahrs_params`` (all angles in radians, times in seconds); build it with
    :meth:`default`, which gives the tuned defaults."""

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
        """One sample (3-vectors; ``mag`` may be None)."""
        g = _in(gyr, "gyr", (3,))
        a = _in(acc, "acc", (3,))
        m = None if mag is None else _in(mag, "mag", (3,))
        _check(lib().bingham_ahrs_update(self._h(), _ptr(g), _ptr(a), _ptr(m)))

    def update_batch(
        self, gyr: ArrayLike, acc: ArrayLike, mag: Optional[ArrayLike] = None, spread: bool = False
    ) -> Union[Array, Tuple[Array, Array]]:
        """n samples (n×3 arrays; ``mag`` n×3 or None). Returns the n×4 quaternions after each
        sample, or ``(quat, spread)`` with the total angular spread (radians, length n) when
        ``spread`` is true. A refused sample raises :class:`BinghamError` (its message names the
        sample); the samples before it have been processed."""
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
