"""The shared library: finding and loading it, and the ctypes signature of every function.

Which file is loaded (the package's ``__init__`` docstring says the order: ``BINGHAM_LIB``, the
library bundled in ``_lib/``, the checkout's ``target/``, the system's), the ``argtypes`` and
``restype`` of every function of ``include/bingham.h`` (:data:`_SIGNATURES`, in the header's
order), the header's constants, and the versions: the library's (:func:`version`) and the
package's (``__version__``, the crate's).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import glob
import os
import re
from typing import Iterator, Optional, Tuple

# The header's BINGHAM_MIN_DIM, BINGHAM_MAX_DIM, BINGHAM_ORTHOGONALITY_TOL, BINGHAM_UNIT_TOL.
MIN_DIM = 2
MAX_DIM = 64
ORTHOGONALITY_TOL = 1e-6
UNIT_TOL = 1e-3


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
    "bingham_filter_surprise": (_STATUS, [ctypes.c_void_p, _D, _D, _D, _D]),
    "bingham_filter_update_gated": (
        _STATUS,
        [ctypes.c_void_p, _D, _D, _D, ctypes.c_double, _D, ctypes.POINTER(ctypes.c_int32)],
    ),
    "bingham_filter_update_vector": (_STATUS, [ctypes.c_void_p, _D, _D, ctypes.c_double]),
    "bingham_filter_log_likelihood_vector": (
        _STATUS,
        [ctypes.c_void_p, _D, _D, ctypes.c_double, _D],
    ),
    "bingham_filter_predict_world": (_STATUS, [ctypes.c_void_p, _D, _D, _D]),
    "bingham_filter_update_world": (_STATUS, [ctypes.c_void_p, _D, _D, _D]),
    "bingham_filter_log_likelihood_world": (_STATUS, [ctypes.c_void_p, _D, _D, _D, _D]),
    "bingham_filter_predict_nonlinear": (_STATUS, [ctypes.c_void_p, _TRANSITION_FN, ctypes.c_void_p, _D, _D]),
    "bingham_filter_update_nonlinear": (_STATUS, [ctypes.c_void_p, _LOG_LIKELIHOOD_FN, ctypes.c_void_p]),
    "bingham_nonlinear_options_default": (_STATUS, [ctypes.c_void_p]),
    "bingham_filter_predict_nonlinear_opts": (
        _STATUS,
        [ctypes.c_void_p, _TRANSITION_FN, ctypes.c_void_p, _D, _D, ctypes.c_void_p, ctypes.c_void_p],
    ),
    "bingham_filter_update_nonlinear_opts": (
        _STATUS,
        [ctypes.c_void_p, _LOG_LIKELIHOOD_FN, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p],
    ),
    "bingham_filter_angular_spread": (_STATUS, [ctypes.c_void_p, _D]),
    "bingham_vector_observation": (_STATUS, [_D, _D, ctypes.c_double, _D, _D]),
    "bingham_noise_from_angle_std": (_STATUS, [_SIZE, ctypes.c_double, _D, _D]),
    "bingham_angular_spread": (_STATUS, [_SIZE, _D, _D, _D]),
    "bingham_ahrs_params_default": (_STATUS, [ctypes.c_double, ctypes.c_void_p]),
    "bingham_ahrs_params_from_rate": (_STATUS, [ctypes.c_double, ctypes.c_void_p]),
    "bingham_ahrs_new": (_STATUS, [ctypes.c_void_p, ctypes.POINTER(ctypes.c_void_p)]),
    "bingham_ahrs_free": (None, [ctypes.c_void_p]),
    "bingham_ahrs_clone": (_STATUS, [ctypes.c_void_p, ctypes.POINTER(ctypes.c_void_p)]),
    "bingham_ahrs_update": (_STATUS, [ctypes.c_void_p, _D, _D, _D]),
    "bingham_ahrs_update_dt": (_STATUS, [ctypes.c_void_p, ctypes.c_double, _D, _D, _D]),
    "bingham_ahrs_update_batch": (_STATUS, [ctypes.c_void_p, _SIZE, _D, _D, _D, _D]),
    "bingham_ahrs_update_batch_spread": (_STATUS, [ctypes.c_void_p, _SIZE, _D, _D, _D, _D, _D]),
    "bingham_ahrs_update_batch_health": (_STATUS, [ctypes.c_void_p, _SIZE, _D, _D, _D, _D, _D, _D]),
    "bingham_ahrs_update_batch_timed": (_STATUS, [ctypes.c_void_p, _SIZE, _D, _D, _D, _D, _D, _D, _D]),
    "bingham_ahrs_health": (_STATUS, [ctypes.c_void_p, ctypes.c_void_p]),
    "bingham_ahrs_smooth": (_STATUS, [ctypes.c_void_p, _SIZE, _D, _D, _D, _D, _D]),
    "bingham_ahrs_smooth_ex": (_STATUS, [ctypes.c_void_p, _SIZE, _D, _D, _D, _D, _D, _D, _D, _D]),
    "bingham_ahrs_quaternion": (_STATUS, [ctypes.c_void_p, _D]),
    "bingham_ahrs_state": (_STATUS, [ctypes.c_void_p, _D, _D]),
    "bingham_ahrs_set_state": (_STATUS, [ctypes.c_void_p, _D, _D]),
    "bingham_ahrs_angular_spread": (_STATUS, [ctypes.c_void_p, _D]),
    "bingham_ahrs_gyro_bias": (_STATUS, [ctypes.c_void_p, _D]),
    "bingham_ahrs_gyro_bias_covariance": (_STATUS, [ctypes.c_void_p, _D]),
    "bingham_ahrs_gyro_scale": (_STATUS, [ctypes.c_void_p, _D]),
    "bingham_ahrs_orientation_covariance": (_STATUS, [ctypes.c_void_p, _D]),
    "bingham_ahrs_mag_latency_estimate": (_STATUS, [ctypes.c_void_p, _D]),
    "bingham_spin_filter_new": (_STATUS, [_D, _D, _D, _D, ctypes.POINTER(ctypes.c_void_p)]),
    "bingham_spin_filter_free": (None, [ctypes.c_void_p]),
    "bingham_spin_filter_clone": (_STATUS, [ctypes.c_void_p, ctypes.POINTER(ctypes.c_void_p)]),
    "bingham_spin_filter_step": (_STATUS, [ctypes.c_void_p, _D, _D, _D, _D, _D, _D]),
    "bingham_spin_filter_log_likelihood": (_STATUS, [ctypes.c_void_p, _D, _D, _D, _D]),
    "bingham_spin_filter_set_state": (_STATUS, [ctypes.c_void_p, _D, _D, _D, _D]),
    "bingham_spin_filter_get_state": (_STATUS, [ctypes.c_void_p, _D, _D, _D, _D]),
    "bingham_spin_filter_orientation_mode": (_STATUS, [ctypes.c_void_p, _D]),
    "bingham_spin_filter_spin_mode": (_STATUS, [ctypes.c_void_p, _D]),
    "bingham_spin_filter_angular_spread": (_STATUS, [ctypes.c_void_p, _D, _D]),
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
    # the installed library's SONAME (`make install`): libbingham.so.<major>, before 1.0
    # libbingham.so.0.<minor> (each 0.x minor version may change the ABI)
    parts = _package_version().split(".")
    if len(parts) >= 2 and parts[0].isdigit() and parts[1].isdigit():
        yield f"libbingham.so.0.{parts[1]}" if parts[0] == "0" else f"libbingham.so.{parts[0]}"


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
        found = cdll.bingham_version().decode() if hasattr(cdll, "bingham_version") else "unknown"
        wanted = _package_version()
        if not compatible(found, wanted):
            errors.append(
                f"{path}: library version {found}, but this package is {wanted}: the structs "
                "passed by value (e.g. the AHRS parameters) differ between these versions; "
                "use the library built with the package"
            )
            continue
        return cdll, (os.path.abspath(path) if os.sep in path else path)
    raise OSError(
        "cannot load libbingham (install the package with `pip install ./python` from the "
        "repository, or set BINGHAM_LIB to a libbingham.so): " + "; ".join(errors)
    )


def compatible(library: str, package: str) -> bool:
    """Whether a library of version ``library`` can serve a package of version ``package``:
    the same major version and, before 1.0, the same minor version (a 0.x release may change
    the layout of the structs the API passes, as 0.3 did for ``bingham_ahrs_params``). An
    ``"unknown"`` version on either side is accepted."""
    try:
        lib_v = [int(v) for v in library.split(".")[:2]]
        pkg_v = [int(v) for v in package.split(".")[:2]]
    except ValueError:
        return True
    if len(lib_v) < 2 or len(pkg_v) < 2:
        return True
    if lib_v[0] != pkg_v[0]:
        return False
    return lib_v[0] != 0 or lib_v[1] == pkg_v[1]


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


def version() -> str:
    """The library version string, e.g. ``"0.1.0"``."""
    return str(lib().bingham_version().decode())
