"""bingham: Bingham distributions on spheres, the recursive Bingham filter, the spin filter and
the Bingham AHRS.

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
  :func:`from_scipy` / :func:`to_scipy`, or SciPy ≥ 1.14's ``scalar_first=True``.)
  :func:`quat_multiply`, :func:`quat_conjugate` and :func:`orientation_error` (total, heading
  and inclination error as the BROAD benchmark defines them) work on ``(..., 4)`` arrays.

Which library is loaded (:func:`library_path` tells): the file named by the environment variable
``BINGHAM_LIB`` if set (for developers: a freshly built ``target/release/libbingham.so``), else the
one bundled in the package, else ``target/release`` or ``target/debug`` of the checkout when the
package is used from the source tree, else the system's (``libbingham.so.0.<minor>`` of ``make install``, found through its SONAME).

Thread safety: the library is thread-safe; the error message read by :class:`BinghamError` is
per thread, so exceptions carry the message of their own call.

The package's modules, one subject each (everything public is re-exported here, import it from
``bingham``): ``_library`` loads the library and binds its functions, :mod:`bingham.errors`
holds :class:`Status`, :class:`BinghamError` and the messages, ``_arrays`` converts arguments,
:mod:`bingham.distribution` has the functions of ``(m, z)``, :mod:`bingham.filter` the
:class:`Filter` (``_callback`` runs its Python callables), :mod:`bingham.spin` the
:class:`SpinFilter` (Glover & Kaelbling's orientation-and-spin filter), :mod:`bingham.ahrs` the
:class:`Ahrs`, :mod:`bingham.smooth` the offline smoother :func:`smooth` (and ``python -m bingham
smooth``, :mod:`bingham.__main__`), :mod:`bingham.quaternion` the quaternion helpers (NumPy only, no library call).
"""

from __future__ import annotations

from ._arrays import Array, ArrayLike as ArrayLike
from .errors import BinghamError, Status, last_error_message, status_str
from ._library import (
    _SIGNATURES as _SIGNATURES,
    MAX_DIM,
    MIN_DIM,
    ORTHOGONALITY_TOL,
    UNIT_TOL,
    _package_version,
    lib,
    library_path,
    version,
)
from .ahrs import HEALTH_THRESHOLD, HEALTH_TIME, LATENCY_ESTIMATE, Ahrs, AhrsHealth, AhrsParams
from .distribution import (
    angular_spread,
    compose,
    deterministic_samples,
    entropy,
    kl_divergence,
    log_normalization_constant,
    log_normalization_constant_saddlepoint,
    log_normalization_hessian,
    log_pdf,
    mle,
    mle_samples,
    mode,
    multiply,
    noise_from_angle_std,
    normalization_constant,
    pdf,
    rotate_left,
    rotate_right,
    sample,
    second_moment,
    vector_observation,
)
from .filter import PREDICT_TOLERANCE, UPDATE_TOLERANCE, Filter, NonlinearReport
from .spin import SpinFilter
from .smooth import Smoothed, smooth
from .quaternion import (
    OrientationError,
    from_scipy,
    orientation_error,
    quat_conjugate,
    quat_multiply,
    to_scipy,
)

__all__ = [
    "NonlinearReport",
    "PREDICT_TOLERANCE",
    "UPDATE_TOLERANCE",
    "__version__",
    "LATENCY_ESTIMATE",
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
    "SpinFilter",
    "vector_observation",
    "noise_from_angle_std",
    "angular_spread",
    "AhrsParams",
    "Ahrs",
    "smooth",
    "Smoothed",
    "quat_multiply",
    "quat_conjugate",
    "OrientationError",
    "orientation_error",
    "to_scipy",
    "from_scipy",
]


#: The package's version: the crate's (``Cargo.toml``), set when the package is built; the
#: bundled library's :func:`version` is the same.
__version__: str = _package_version()
