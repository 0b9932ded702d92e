"""Functions of Bingham distributions given as ``(m, z)`` (no state): the normalization
constant and its derivatives, moments and maximum-likelihood fits, products and compositions,
densities, entropy and KL divergence, random and deterministic samples, rotations, and the
rotation models of d = 2, 4 (vector observations, isotropic noise, angular spread)."""

from __future__ import annotations

import ctypes
from typing import Any, Optional, Tuple, Union

import numpy as np

from ._arrays import Array, ArrayLike, _dist, _in, _points, _ptr, _vec
from .errors import _check
from ._library import _SIZE, lib

__all__ = [
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
    "vector_observation",
    "noise_from_angle_std",
    "angular_spread",
]


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
      exists (for some z with d = 4: a very broad axis next to a moderately sharp one; how
      often: docs/accuracy/nonlinear.md) the ``2d − 1`` points of ``"tac2016"`` with
      ``lam = 0.5`` instead (``reproduced == 2``). ``lam`` is ignored.
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


# ---- rotations (d = 2, 4): vector observations, noise, angular spread ---------------------------


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
