/*
 * bingham.hpp -- header-only C++17 interface over the C API of the bingham library (bingham.h).
 * SPDX-License-Identifier: MIT OR Apache-2.0
 *
 * Nothing of the math lives here: every function calls the C ABI, turns a non-OK status into a
 * bingham::Error exception and owns the handles (RAII, move-only). Link the library as for C
 * (`-lbingham`, or CMake's `bingham::bingham`).
 *
 * Conventions (as in bingham.h):
 * - A distribution is (M, z): M d x d orthogonal, stored ROW-MAJOR in a std::vector<double>; its
 *   COLUMNS are the principal directions, column i belongs to z[i], the LAST column is the mode.
 *   Results come with z ascending and z[d-1] = 0.
 * - F(Z) uses the surface measure of the sphere: F(0) = 2*pi (d = 2), 4*pi (d = 3), 2*pi^2 (d = 4).
 * - Quaternions are SCALAR FIRST, (w, x, y, z), and map sensor to world: v_world = q v_sensor q*.
 *   bingham::Quaternion has named fields; it converts to and from Eigen::Quaterniond by the
 *   named accessors w(), x(), y(), z() -- never through Eigen's coeffs(), which is (x, y, z, w).
 *   Complex numbers (d = 2, axes in the plane) are std::complex<double> (re, im).
 * - Angles are radians unless a function name ends in _deg; gyroscope rad/s, accelerometer m/s^2.
 *
 * Eigen support: include <Eigen/Core> and <Eigen/Geometry> (or <Eigen/Dense> with
 * <Eigen/Geometry>) BEFORE this header, or include "bingham_eigen.hpp", which does both. Then
 * bingham::Quaternion converts to/from Eigen::Quaterniond, Distribution is constructible from any
 * Eigen matrix for M (either storage order: entries are read as M(i, j)) and vector for z, and
 * the functions taking points and 3-vectors accept Eigen vectors. Define BINGHAM_NO_EIGEN to turn
 * the detection off. The two configurations live in different inline namespaces, so translation
 * units that differ in it do not violate the one-definition rule (their Filter types differ).
 *
 * Thread safety: as the C API -- one thread at a time per Filter/SpinFilter/Ahrs object;
 * everything else may run concurrently.
 */
#ifndef BINGHAM_HPP
#define BINGHAM_HPP

#include <array>
#include <cmath>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "bingham.h"

#if !defined(BINGHAM_NO_EIGEN) && defined(EIGEN_WORLD_VERSION) && defined(EIGEN_GEOMETRY_MODULE_H)
#define BINGHAM_HPP_EIGEN 1
#else
#define BINGHAM_HPP_EIGEN 0
#endif

namespace bingham {

/// The calling thread's last error message of the C library (empty if nothing failed yet).
inline std::string last_error_message() {
    std::size_t len = 0;
    bingham_last_error_message(nullptr, 0, &len);
    std::string msg(len + 1, '\0');
    bingham_last_error_message(&msg[0], msg.size(), &len);
    msg.resize(len < msg.size() ? len : msg.size() - 1);
    return msg;
}

/// The version of the library actually loaded, "MAJOR.MINOR.PATCH".
inline std::string version() { return bingham_version(); }

/// The exception thrown by every wrapper function: the C status and the library's message.
///
/// `what()` is the message of `bingham_last_error_message()` at the failing call (e.g.
/// "bingham_mle: s: invalid argument: not symmetric ..."), or, for size mismatches caught by the
/// wrapper before calling the library, a message naming the C++ function. On any Error, no
/// output and no object has been changed (strong exception guarantee).
class Error : public std::runtime_error {
public:
    Error(bingham_status status, const std::string &message)
        : std::runtime_error(message), status_(status) {}
    /// The C status (never BINGHAM_OK).
    bingham_status status() const noexcept { return status_; }
    /// The message (same as what()).
    std::string message() const { return what(); }

private:
    bingham_status status_;
};

namespace detail {
inline void check(bingham_status st) {
    if (st != BINGHAM_OK) throw Error(st, last_error_message());
}
inline void require(bool ok, bingham_status st, const char *where, const char *what) {
    if (!ok) throw Error(st, std::string(where) + ": " + bingham_status_str(static_cast<int>(st)) + ": " + what);
}
inline void require_dim(bool ok, const char *where, const char *what) {
    require(ok, BINGHAM_ERR_INVALID_DIMENSION, where, what);
}
// C callbacks (bingham_transition_fn, bingham_log_likelihood_fn) calling a C++ callable: an
// exception never crosses the C library; it is stored, the callback returns 1 (the library
// stops and leaves the filter unchanged), and the wrapper rethrows it after the call.
template <class F>
struct Callback {
    F *fn;
    std::exception_ptr error;
};
template <class F>
int transition_trampoline(const double *x_in, double *x_out, void *user_data) noexcept {
    auto *c = static_cast<Callback<F> *>(user_data);
    try {
        (*c->fn)(x_in, x_out);
        return 0;
    } catch (...) {
        c->error = std::current_exception();
        return 1;
    }
}
template <class F>
int log_likelihood_trampoline(const double *x, double *log_l, void *user_data) noexcept {
    auto *c = static_cast<Callback<F> *>(user_data);
    try {
        *log_l = static_cast<double>((*c->fn)(x));
        return 0;
    } catch (...) {
        c->error = std::current_exception();
        return 1;
    }
}
// Rethrows the callable's exception if there was one, else checks the status.
template <class F>
void check_callback(bingham_status st, const Callback<F> &c) {
    if (c.error) std::rethrow_exception(c.error);
    check(st);
}
}  // namespace detail

#if BINGHAM_HPP_EIGEN
inline namespace with_eigen {
#else
inline namespace without_eigen {
#endif

/// A unit quaternion, SCALAR FIRST: w + x i + y j + z k (named fields, so the order cannot be
/// mixed up). Orientations map sensor to world. With Eigen, converts implicitly to and from
/// Eigen::Quaterniond (mapping w, x, y, z by name).
struct Quaternion {
    double w = 1, x = 0, y = 0, z = 0;
    /// The identity (1, 0, 0, 0).
    Quaternion() = default;
    /// (w, x, y, z), scalar first.
    Quaternion(double w_, double x_, double y_, double z_) : w(w_), x(x_), y(y_), z(z_) {}
    /// The scalar-first array (w, x, y, z).
    std::array<double, 4> array() const { return {w, x, y, z}; }
    /// From a scalar-first array (w, x, y, z).
    static Quaternion from_array(const double *wxyz) { return {wxyz[0], wxyz[1], wxyz[2], wxyz[3]}; }
#if BINGHAM_HPP_EIGEN
    /// From any Eigen quaternion (Quaterniond, Map<Quaterniond>, ...): by w(), x(), y(), z().
    template <class Derived>
    Quaternion(const Eigen::QuaternionBase<Derived> &q)  // NOLINT: implicit on purpose
        : w(q.w()), x(q.x()), y(q.y()), z(q.z()) {}
    /// To Eigen::Quaterniond(w, x, y, z) (Eigen's constructor is scalar first too).
    operator Eigen::Quaterniond() const { return Eigen::Quaterniond(w, x, y, z); }  // NOLINT
    /// The same as Eigen::Quaterniond.
    Eigen::Quaterniond eigen() const { return *this; }
#endif
};

#if BINGHAM_HPP_EIGEN
/// The type orientation estimates are returned as (Ahrs::quaternion(), Filter::mode_quaternion(),
/// mode_quaternion()): Eigen::Quaterniond where Eigen is enabled, so that
/// `auto q = ahrs.quaternion(); q.angularDistance(truth)` works; bingham::Quaternion otherwise.
/// The two convert to each other implicitly (by w, x, y, z).
using EstimateQuaternion = Eigen::Quaterniond;
#else
/// The type orientation estimates are returned as: bingham::Quaternion (Eigen::Quaterniond
/// where Eigen is enabled).
using EstimateQuaternion = Quaternion;
#endif

/// A Bingham distribution (M, z) on the unit sphere S^{d-1} in R^d: a plain value.
///
/// `M` is d*d ROW-MAJOR (orthogonal; columns are the principal directions, column i belongs to
/// `z[i]`, the last column is the mode after normalization); `z` has d entries (any order and
/// shift on input; library results are ascending with z[d-1] = 0).
struct Distribution {
    std::size_t d = 0;
    std::vector<double> M;  ///< d x d, row-major
    std::vector<double> z;  ///< d concentrations

    Distribution() = default;
    /// From a row-major M (d*d entries) and z (d entries); throws Error
    /// (BINGHAM_ERR_INVALID_DIMENSION) if the sizes do not match.
    Distribution(std::vector<double> M_, std::vector<double> z_) : d(z_.size()), M(std::move(M_)), z(std::move(z_)) {
        validate("bingham::Distribution");
    }
    /// Throws Error (BINGHAM_ERR_INVALID_DIMENSION) unless M has d*d and z has d entries.
    void validate(const char *where) const {
        detail::require_dim(d >= 1 && z.size() == d && M.size() == d * d, where,
                            "Distribution needs z of size d and M of size d*d");
    }
    /// Entry M(i, j) of the row-major matrix.
    double m(std::size_t i, std::size_t j) const { return M[i * d + j]; }

#if BINGHAM_HPP_EIGEN
    /// From Eigen: M any d x d matrix expression (row- or column-major; read as M(i, j) and stored
    /// row-major), z any vector of d entries.
    template <class DM, class DZ>
    Distribution(const Eigen::MatrixBase<DM> &M_, const Eigen::MatrixBase<DZ> &z_) : d(static_cast<std::size_t>(z_.size())) {
        detail::require_dim(z_.cols() == 1 || z_.rows() == 1, "bingham::Distribution", "z must be a vector");
        detail::require_dim(static_cast<std::size_t>(M_.rows()) == d && static_cast<std::size_t>(M_.cols()) == d,
                            "bingham::Distribution", "M must be d x d with d = z.size()");
        M.resize(d * d);
        z.resize(d);
        for (std::size_t i = 0; i < d; ++i) {
            z[i] = z_(static_cast<Eigen::Index>(i));
            for (std::size_t j = 0; j < d; ++j)
                M[i * d + j] = M_(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
        }
    }
    /// M as an Eigen matrix (assign to Matrix4d / Matrix2d or a row-major type as you like).
    Eigen::MatrixXd matrix() const {
        Eigen::MatrixXd r(static_cast<Eigen::Index>(d), static_cast<Eigen::Index>(d));
        for (std::size_t i = 0; i < d; ++i)
            for (std::size_t j = 0; j < d; ++j) r(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = m(i, j);
        return r;
    }
    /// z as an Eigen vector.
    Eigen::VectorXd concentrations() const {
        return Eigen::Map<const Eigen::VectorXd>(z.data(), static_cast<Eigen::Index>(z.size()));
    }
#endif
};

namespace impl {
// Quaternion overloads of functions that also take std::vector<double> are templates, so that
// a braced list {w, x, y, z} is not ambiguous (it goes to the std::vector overload).
template <class Q>
#if BINGHAM_HPP_EIGEN
using if_quaternion = std::enable_if_t<std::is_same_v<Q, Quaternion> ||
                                           std::is_base_of_v<Eigen::QuaternionBase<Q>, Q>, int>;
#else
using if_quaternion = std::enable_if_t<std::is_same_v<Q, Quaternion>, int>;
#endif
inline void check_point(const Distribution &b, std::size_t n, const char *where) {
    b.validate(where);
    detail::require_dim(n == b.d, where, "the vector must have d entries");
}
#if BINGHAM_HPP_EIGEN
// Copies an Eigen vector expression into a std::vector.
template <class D>
std::vector<double> to_vector(const Eigen::MatrixBase<D> &v, const char *where) {
    detail::require_dim(v.cols() == 1 || v.rows() == 1, where, "expected a vector");
    std::vector<double> r(static_cast<std::size_t>(v.size()));
    for (Eigen::Index i = 0; i < v.size(); ++i) r[static_cast<std::size_t>(i)] = v(i);
    return r;
}
template <class D>
std::array<double, 3> to_array3(const Eigen::MatrixBase<D> &v, const char *where) {
    detail::require_dim(v.size() == 3 && (v.cols() == 1 || v.rows() == 1), where, "expected a 3-vector");
    return {v(0), v(1), v(2)};
}
// Copies an n x d Eigen matrix (one point per row, either storage order) into row-major storage.
template <class D>
std::vector<double> rows_to_vector(const Eigen::MatrixBase<D> &x) {
    std::vector<double> r(static_cast<std::size_t>(x.size()));
    std::size_t k = 0;
    for (Eigen::Index i = 0; i < x.rows(); ++i)
        for (Eigen::Index j = 0; j < x.cols(); ++j) r[k++] = x(i, j);
    return r;
}
#endif
}  // namespace impl

// ---- normalization constant ------------------------------------------------------------------

/// A value with its gradient (and, from log_normalization_hessian(), the row-major Hessian).
struct ValueGradient {
    double value = 0;
    std::vector<double> gradient;  ///< in the order of the input z
    std::vector<double> hessian;   ///< d x d row-major (log_normalization_hessian() only)
};

/// F(Z) = integral over S^{d-1} of exp(x^T Z x) (surface measure). Throws
/// Error(BINGHAM_ERR_NUMERICAL) where F overflows a double: use log_normalization_constant().
inline double normalization_constant(const std::vector<double> &z) {
    double f = 0;
    detail::check(bingham_normalization_constant(z.size(), z.data(), &f, nullptr));
    return f;
}
/// F(Z) and dF/dz_i.
inline ValueGradient normalization_constant_gradient(const std::vector<double> &z) {
    ValueGradient r;
    r.gradient.resize(z.size());
    detail::check(bingham_normalization_constant(z.size(), z.data(), &r.value, r.gradient.data()));
    return r;
}
/// log F(Z), finite for every finite z.
inline double log_normalization_constant(const std::vector<double> &z) {
    double f = 0;
    detail::check(bingham_log_normalization_constant(z.size(), z.data(), &f, nullptr));
    return f;
}
/// log F(Z) and d log F/dz_i = E[x_i^2] in the principal frame (the moments; they sum to 1).
inline ValueGradient log_normalization_constant_gradient(const std::vector<double> &z) {
    ValueGradient r;
    r.gradient.resize(z.size());
    detail::check(bingham_log_normalization_constant(z.size(), z.data(), &r.value, r.gradient.data()));
    return r;
}
/// log F(Z) with gradient and Hessian (exact).
inline ValueGradient log_normalization_hessian(const std::vector<double> &z) {
    ValueGradient r;
    r.gradient.resize(z.size());
    r.hessian.resize(z.size() * z.size());
    detail::check(
        bingham_log_normalization_hessian(z.size(), z.data(), &r.value, r.gradient.data(), r.hessian.data()));
    return r;
}
/// APPROXIMATE log F and gradient (Kume & Wood saddlepoint), for comparison with other libraries.
inline ValueGradient log_normalization_constant_saddlepoint(const std::vector<double> &z) {
    ValueGradient r;
    r.gradient.resize(z.size());
    detail::check(bingham_log_normalization_constant_saddlepoint(z.size(), z.data(), &r.value, r.gradient.data()));
    return r;
}

// ---- distributions ---------------------------------------------------------------------------

/// The second moment S = E[x x^T] = M diag(omega) M^T, d x d row-major (trace 1).
inline std::vector<double> second_moment(const Distribution &b) {
    b.validate("bingham::second_moment");
    std::vector<double> s(b.d * b.d);
    detail::check(bingham_second_moment(b.d, b.M.data(), b.z.data(), s.data()));
    return s;
}

/// Maximum-likelihood (moment-matched) Bingham distribution for a second-moment matrix S
/// (d x d row-major, symmetric PSD; any positive multiple).
inline Distribution mle(std::size_t d, const std::vector<double> &s) {
    detail::require_dim(s.size() == d * d, "bingham::mle", "S must have d*d entries");
    Distribution r;
    r.d = d;
    r.M.resize(d * d);
    r.z.resize(d);
    detail::check(bingham_mle(d, s.data(), r.M.data(), r.z.data()));
    return r;
}

/// Maximum-likelihood fit to n unit samples (n x d row-major), with optional weights (empty: equal).
inline Distribution mle_samples(std::size_t d, const std::vector<double> &x, const std::vector<double> &w = {}) {
    detail::require_dim(d > 0 && x.size() % d == 0, "bingham::mle_samples", "x must have n*d entries");
    const std::size_t n = x.size() / d;
    detail::require_dim(w.empty() || w.size() == n, "bingham::mle_samples", "w must be empty or have n entries");
    Distribution r;
    r.d = d;
    r.M.resize(d * d);
    r.z.resize(d);
    detail::check(bingham_mle_samples(d, n, x.data(), w.empty() ? nullptr : w.data(), r.M.data(), r.z.data()));
    return r;
}

namespace impl {
using Binary = bingham_status (*)(size_t, const double *, const double *, const double *, const double *, double *,
                                  double *);
inline Distribution binary(Binary fn, const Distribution &a, const Distribution &b, const char *where) {
    a.validate(where);
    b.validate(where);
    detail::require_dim(a.d == b.d, where, "the two distributions differ in d");
    Distribution r;
    r.d = a.d;
    r.M.resize(a.d * a.d);
    r.z.resize(a.d);
    detail::check(fn(a.d, a.M.data(), a.z.data(), b.M.data(), b.z.data(), r.M.data(), r.z.data()));
    return r;
}
}  // namespace impl

/// The product of the densities (Bayes' rule), renormalized. Exact.
inline Distribution multiply(const Distribution &a, const Distribution &b) {
    return impl::binary(bingham_multiply, a, b, "bingham::multiply");
}
/// The moment-matched distribution of x (+) y (complex product d = 2, Hamilton product d = 4).
inline Distribution compose(const Distribution &a, const Distribution &b) {
    return impl::binary(bingham_compose, a, b, "bingham::compose");
}
/// The distribution of u (+) x (d = 2, 4), exact.
inline Distribution rotate_left(const Distribution &b, const std::vector<double> &u) {
    impl::check_point(b, u.size(), "bingham::rotate_left");
    Distribution r = b;
    detail::check(bingham_rotate_left(b.d, b.M.data(), b.z.data(), u.data(), r.M.data(), r.z.data()));
    return r;
}
/// The distribution of x (+) u (d = 2, 4), exact.
inline Distribution rotate_right(const Distribution &b, const std::vector<double> &u) {
    impl::check_point(b, u.size(), "bingham::rotate_right");
    Distribution r = b;
    detail::check(bingham_rotate_right(b.d, b.M.data(), b.z.data(), u.data(), r.M.data(), r.z.data()));
    return r;
}
/// u (+) x for a quaternion u (d = 4).
template <class Q, impl::if_quaternion<Q> = 0>
Distribution rotate_left(const Distribution &b, const Q &u) {
    const auto a = Quaternion(u).array();
    return rotate_left(b, std::vector<double>(a.begin(), a.end()));
}
/// x (+) u for a quaternion u (d = 4).
template <class Q, impl::if_quaternion<Q> = 0>
Distribution rotate_right(const Distribution &b, const Q &u) {
    const auto a = Quaternion(u).array();
    return rotate_right(b, std::vector<double>(a.begin(), a.end()));
}

/// The mode (a unit vector of d entries; -mode is a mode as well).
inline std::vector<double> mode(const Distribution &b) {
    b.validate("bingham::mode");
    std::vector<double> r(b.d);
    detail::check(bingham_mode(b.d, b.M.data(), b.z.data(), r.data()));
    return r;
}
/// The mode of a distribution of rotations (d = 4) as a quaternion.
inline EstimateQuaternion mode_quaternion(const Distribution &b) {
    detail::require_dim(b.d == 4, "bingham::mode_quaternion", "needs d = 4");
    return Quaternion::from_array(mode(b).data());
}

/// The density at n points (n x d row-major), surface measure.
inline std::vector<double> pdf_points(const Distribution &b, const std::vector<double> &x) {
    b.validate("bingham::pdf_points");
    detail::require_dim(x.size() % b.d == 0, "bingham::pdf_points", "x must have n*d entries");
    std::vector<double> p(x.size() / b.d);
    detail::check(bingham_pdf(b.d, b.M.data(), b.z.data(), p.size(), x.empty() ? nullptr : x.data(), p.data()));
    return p;
}
/// The log density at n points (n x d row-major).
inline std::vector<double> log_pdf_points(const Distribution &b, const std::vector<double> &x) {
    b.validate("bingham::log_pdf_points");
    detail::require_dim(x.size() % b.d == 0, "bingham::log_pdf_points", "x must have n*d entries");
    std::vector<double> p(x.size() / b.d);
    detail::check(bingham_log_pdf(b.d, b.M.data(), b.z.data(), p.size(), x.empty() ? nullptr : x.data(), p.data()));
    return p;
}
/// The density at one unit vector x (d entries).
inline double pdf(const Distribution &b, const std::vector<double> &x) {
    impl::check_point(b, x.size(), "bingham::pdf");
    return pdf_points(b, x)[0];
}
/// The log density at one unit vector x (d entries).
inline double log_pdf(const Distribution &b, const std::vector<double> &x) {
    impl::check_point(b, x.size(), "bingham::log_pdf");
    return log_pdf_points(b, x)[0];
}
/// The density at a quaternion (d = 4).
template <class Q, impl::if_quaternion<Q> = 0>
double pdf(const Distribution &b, const Q &q) {
    const auto a = Quaternion(q).array();
    return pdf(b, std::vector<double>(a.begin(), a.end()));
}
/// The log density at a quaternion (d = 4).
template <class Q, impl::if_quaternion<Q> = 0>
double log_pdf(const Distribution &b, const Q &q) {
    const auto a = Quaternion(q).array();
    return log_pdf(b, std::vector<double>(a.begin(), a.end()));
}

/// Differential entropy (nats, surface measure).
inline double entropy(const Distribution &b) {
    b.validate("bingham::entropy");
    double h = 0;
    detail::check(bingham_entropy(b.d, b.M.data(), b.z.data(), &h));
    return h;
}
/// KL(a || b) in nats.
inline double kl_divergence(const Distribution &a, const Distribution &b) {
    a.validate("bingham::kl_divergence");
    b.validate("bingham::kl_divergence");
    detail::require_dim(a.d == b.d, "bingham::kl_divergence", "the two distributions differ in d");
    double kl = 0;
    detail::check(bingham_kl_divergence(a.d, a.M.data(), a.z.data(), b.M.data(), b.z.data(), &kl));
    return kl;
}

/// n samples (n x d row-major unit vectors), deterministic in `seed`.
inline std::vector<double> sample(const Distribution &b, std::size_t n, std::uint64_t seed) {
    b.validate("bingham::sample");
    std::vector<double> x(n * b.d);
    detail::check(bingham_sample(b.d, b.M.data(), b.z.data(), seed, n, x.empty() ? nullptr : x.data()));
    return x;
}

/// The angular spread in radians (d = 2, 4): entries 0..d-2 along the principal directions,
/// entry d-1 the total (d = 4: the RMS of 2 sin(theta/2), ~ the RMS rotation angle from the mode).
inline std::vector<double> angular_spread(const Distribution &b) {
    b.validate("bingham::angular_spread");
    std::vector<double> s(b.d);
    detail::check(bingham_angular_spread(b.d, b.M.data(), b.z.data(), s.data()));
    return s;
}

/// Isotropic rotation noise with angular standard deviation `sigma` in RADIANS (per axis, d = 4;
/// the angle, d = 2), mode at the identity: the process or measurement noise of a Filter.
inline Distribution noise_from_angle_std(std::size_t d, double sigma) {
    Distribution r;
    r.d = d;
    r.M.resize(d * d);
    r.z.resize(d);
    detail::check(bingham_noise_from_angle_std(d, sigma, r.M.data(), r.z.data()));
    return r;
}
/// As noise_from_angle_std(), with `sigma_deg` in DEGREES.
inline Distribution noise_from_angle_std_deg(std::size_t d, double sigma_deg) {
    return noise_from_angle_std(d, sigma_deg * (3.14159265358979323846 / 180.0));
}

/// The likelihood of a measured unit direction `body` (sensor frame) of the known unit direction
/// `reference` (world frame), von Mises-Fisher noise `kappa` (~ 1/sigma^2), as a Bingham
/// distribution of the orientation (d = 4).
inline Distribution vector_observation(const std::array<double, 3> &body, const std::array<double, 3> &reference,
                                       double kappa) {
    Distribution r;
    r.d = 4;
    r.M.resize(16);
    r.z.resize(4);
    detail::check(bingham_vector_observation(body.data(), reference.data(), kappa, r.M.data(), r.z.data()));
    return r;
}

#if BINGHAM_HPP_EIGEN
/// The density at one point given as an Eigen vector (d entries).
template <class D>
double pdf(const Distribution &b, const Eigen::MatrixBase<D> &x) {
    return pdf(b, impl::to_vector(x, "bingham::pdf"));
}
/// The log density at one point given as an Eigen vector (d entries).
template <class D>
double log_pdf(const Distribution &b, const Eigen::MatrixBase<D> &x) {
    return log_pdf(b, impl::to_vector(x, "bingham::log_pdf"));
}
/// The density at n points, the rows of an n x d Eigen matrix (either storage order).
template <class D>
Eigen::VectorXd pdf_points(const Distribution &b, const Eigen::MatrixBase<D> &x) {
    detail::require_dim(static_cast<std::size_t>(x.cols()) == b.d, "bingham::pdf_points", "x must be n x d");
    const std::vector<double> p = pdf_points(b, impl::rows_to_vector(x));
    return Eigen::Map<const Eigen::VectorXd>(p.data(), static_cast<Eigen::Index>(p.size()));
}
/// The log density at n points, the rows of an n x d Eigen matrix (either storage order).
template <class D>
Eigen::VectorXd log_pdf_points(const Distribution &b, const Eigen::MatrixBase<D> &x) {
    detail::require_dim(static_cast<std::size_t>(x.cols()) == b.d, "bingham::log_pdf_points", "x must be n x d");
    const std::vector<double> p = log_pdf_points(b, impl::rows_to_vector(x));
    return Eigen::Map<const Eigen::VectorXd>(p.data(), static_cast<Eigen::Index>(p.size()));
}
/// n samples as the rows of an n x d Eigen matrix.
inline Eigen::MatrixXd sample_matrix(const Distribution &b, std::size_t n, std::uint64_t seed) {
    const std::vector<double> x = sample(b, n, seed);
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    return Eigen::Map<const RowMajor>(x.data(), static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(b.d));
}
/// The second moment as an Eigen matrix.
inline Eigen::MatrixXd second_moment_matrix(const Distribution &b) {
    const std::vector<double> s = second_moment(b);
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    return Eigen::Map<const RowMajor>(s.data(), static_cast<Eigen::Index>(b.d), static_cast<Eigen::Index>(b.d));
}
/// The MLE for a second-moment matrix given as an Eigen matrix (either storage order).
template <class D>
Distribution mle(const Eigen::MatrixBase<D> &s) {
    detail::require_dim(s.rows() == s.cols(), "bingham::mle", "S must be square");
    return mle(static_cast<std::size_t>(s.rows()), impl::rows_to_vector(s));
}
/// vector_observation() with Eigen 3-vectors.
template <class DB, class DR>
Distribution vector_observation(const Eigen::MatrixBase<DB> &body, const Eigen::MatrixBase<DR> &reference,
                                double kappa) {
    return vector_observation(impl::to_array3(body, "bingham::vector_observation"),
                              impl::to_array3(reference, "bingham::vector_observation"), kappa);
}
#endif

// ---- the recursive Bingham filter ------------------------------------------------------------

/// How the nonlinear steps control their error (bingham_nonlinear_options); the defaults are
/// the library's: tolerance 0 = the step's own default (BINGHAM_NONLINEAR_PREDICT_TOLERANCE,
/// BINGHAM_NONLINEAR_UPDATE_TOLERANCE), mode tolerance 0.05 spreads, 20000 calls.
struct NonlinearOptions {
    /// Largest accepted error estimate of any entry of the second moment (0: the default).
    double tolerance = 0.0;
    /// Update only: largest accepted mode error estimate, as a fraction of the spread.
    double mode_tolerance = 0.05;
    /// The most callback calls of one step.
    std::size_t max_calls = 20000;
    /// The C struct.
    bingham_nonlinear_options c() const noexcept { return {tolerance, mode_tolerance, max_calls}; }
};

/// What a nonlinear step measured (see bingham_nonlinear_report).
using NonlinearReport = bingham_nonlinear_report;

/// The recursive Bingham filter (d = 2: axes as complex numbers; d = 4: orientations as
/// quaternions, scalar first). Owns a `bingham_filter *`; move-only, copy with clone().
///
/// Model: x[k+1] = x[k] (+) w[k], measurement = x[k] (+) v[k], with Bingham noises w, v (pass the
/// same noise object every step: the library caches its moments); the world-frame steps
/// predict_world(), update_world(), log_likelihood_world() have Glover & Kaelbling's model
/// x[k+1] = w[k] o u[k] o x[k], y = v o x (noises on the left). A moved-from Filter is empty:
/// its methods throw Error(BINGHAM_ERR_NULL_ARGUMENT); destroying or assigning to it is fine.
class Filter {
public:
    /// A filter with the initial estimate `initial` (d = 2 or 4).
    explicit Filter(const Distribution &initial) {
        initial.validate("bingham::Filter");
        detail::check(bingham_filter_new(initial.d, initial.M.data(), initial.z.data(), &f_));
        d_ = initial.d;
    }
    ~Filter() { bingham_filter_free(f_); }
    Filter(Filter &&o) noexcept : f_(std::exchange(o.f_, nullptr)), d_(std::exchange(o.d_, 0)) {}
    Filter &operator=(Filter &&o) noexcept {
        if (this != &o) {
            bingham_filter_free(f_);
            f_ = std::exchange(o.f_, nullptr);
            d_ = std::exchange(o.d_, 0);
        }
        return *this;
    }
    Filter(const Filter &) = delete;
    Filter &operator=(const Filter &) = delete;

    /// An independent copy (state and cached noise).
    Filter clone() const {
        require("bingham::Filter::clone");
        bingham_filter *c = nullptr;
        detail::check(bingham_filter_clone(f_, &c));
        return Filter(c, d_);
    }
    /// False for a moved-from filter.
    explicit operator bool() const noexcept { return f_ != nullptr; }
    /// The dimension, 2 or 4 (0 when empty).
    std::size_t dim() const noexcept { return d_; }
    /// The C handle (owned by this object).
    bingham_filter *get() noexcept { return f_; }
    const bingham_filter *get() const noexcept { return f_; }

    /// Prediction: x <- x (+) w, w ~ noise (e.g. noise_from_angle_std_deg(4, 0.5)).
    void predict(const Distribution &noise) {
        check_noise(noise, "bingham::Filter::predict");
        detail::check(bingham_filter_predict(f_, noise.M.data(), noise.z.data()));
    }
    /// Nonlinear prediction: x <- a(x) (+) w, w ~ noise (bingham_filter_predict_nonlinear).
    /// `a` is any callable `void(const double *x_in, double *x_out)`: x_in is a unit vector of
    /// d() entries, x_out receives the unit vector a(x_in) (d() entries; a(-x) = +-a(x) is the
    /// caller's contract). Called at the deterministic samples of the state (3 for d = 2, 19 for
    /// d = 4) and, where their error estimate asks, at sampled points (default tolerances; see
    /// the overload with NonlinearOptions), on this thread. An exception thrown by `a` stops the prediction and
    /// is rethrown here; a non-finite or non-unit output throws Error(BINGHAM_ERR_CALLBACK). In
    /// both cases the filter is unchanged.
    template <class F>
    void predict_nonlinear(F &&a, const Distribution &noise) {
        check_noise(noise, "bingham::Filter::predict_nonlinear");
        using Fn = std::remove_reference_t<F>;
        detail::Callback<Fn> c{&a, nullptr};
        bingham_status st = bingham_filter_predict_nonlinear(f_, &detail::transition_trampoline<Fn>, &c,
                                                             noise.M.data(), noise.z.data());
        detail::check_callback(st, c);
    }
    /// Nonlinear prediction with its error controlled by `opts` (bingham_filter_predict_nonlinear_opts):
    /// the result's error estimate (3 standard errors of any entry of the predicted second
    /// moment) meets `opts.tolerance`. Returns what was measured; a tolerance not met within
    /// `opts.max_calls` throws Error(BINGHAM_ERR_NOT_CONVERGED) with the estimate in its message
    /// (the filter unchanged). The method: docs/design.md, "Nonlinear steps".
    template <class F>
    NonlinearReport predict_nonlinear(F &&a, const Distribution &noise, const NonlinearOptions &opts) {
        check_noise(noise, "bingham::Filter::predict_nonlinear");
        using Fn = std::remove_reference_t<F>;
        detail::Callback<Fn> c{&a, nullptr};
        bingham_nonlinear_options o = opts.c();
        NonlinearReport r{};
        bingham_status st = bingham_filter_predict_nonlinear_opts(
            f_, &detail::transition_trampoline<Fn>, &c, noise.M.data(), noise.z.data(), &o, &r);
        detail::check_callback(st, c);
        return r;
    }
    /// Nonlinear update: posterior prop. to prior(x) L(x) (bingham_filter_update_nonlinear).
    /// `log_l` is any callable `double(const double *x)` returning log L(x) (finite) for a unit
    /// vector x of d() entries (L(-x) = L(x) is the caller's contract); called at the
    /// deterministic samples of a few rounds and at sampled points (default tolerances; see the
    /// overload with NonlinearOptions), on this thread. An exception thrown by
    /// `log_l` stops the update and is rethrown here; a non-finite value throws
    /// Error(BINGHAM_ERR_CALLBACK). In both cases the filter is unchanged.
    template <class F>
    void update_nonlinear(F &&log_l) {
        require("bingham::Filter::update_nonlinear");
        using Fn = std::remove_reference_t<F>;
        detail::Callback<Fn> c{&log_l, nullptr};
        bingham_status st = bingham_filter_update_nonlinear(f_, &detail::log_likelihood_trampoline<Fn>, &c);
        detail::check_callback(st, c);
    }

    /// Nonlinear update with its error controlled by `opts` (bingham_filter_update_nonlinear_opts):
    /// every update is checked by sampling; its error estimates (3 standard errors of the
    /// second moment's entries and of the mode) meet `opts.tolerance` and `opts.mode_tolerance`.
    /// Returns what was measured; tolerances not met within `opts.max_calls` throw
    /// Error(BINGHAM_ERR_NOT_CONVERGED) with the estimates in its message (the filter unchanged).
    /// The method: docs/design.md, "Nonlinear steps".
    template <class F>
    NonlinearReport update_nonlinear(F &&log_l, const NonlinearOptions &opts) {
        require("bingham::Filter::update_nonlinear");
        using Fn = std::remove_reference_t<F>;
        detail::Callback<Fn> c{&log_l, nullptr};
        bingham_nonlinear_options o = opts.c();
        NonlinearReport r{};
        bingham_status st =
            bingham_filter_update_nonlinear_opts(f_, &detail::log_likelihood_trampoline<Fn>, &c, &o, &r);
        detail::check_callback(st, c);
        return r;
    }

    /// Prediction with a body-frame rotation increment (d = 4), e.g. from a gyroscope.
    void predict_rotation(const Quaternion &u, const Distribution &noise) { predict_rotation_raw(vec(u), noise); }
    /// Prediction turning an axis (d = 2) by the unit complex number u.
    void predict_rotation(std::complex<double> u, const Distribution &noise) { predict_rotation_raw(vec(u), noise); }

    /// Update with a measured orientation (d = 4).
    void update(const Quaternion &measurement, const Distribution &noise) { update_raw(vec(measurement), noise); }
    /// Update with a measured axis (d = 2).
    void update(std::complex<double> measurement, const Distribution &noise) { update_raw(vec(measurement), noise); }

    double log_likelihood(const Quaternion &measurement, const Distribution &noise) const {
        return log_likelihood_raw(vec(measurement), noise);
    }
    double log_likelihood(std::complex<double> measurement, const Distribution &noise) const {
        return log_likelihood_raw(vec(measurement), noise);
    }

    /// The outcome of update_gated().
    struct Gated {
        bool accepted;    ///< whether the update was applied
        double surprise;  ///< the measurement's surprise (see surprise())
    };
    /// The measurement's surprise 2 (log p(y_hat) - log p(measurement)) >= 0 (y_hat: the modes of
    /// state and noise composed): chi-square with d - 1 degrees of freedom when the model holds
    /// (mean 3 for quaternions, above 16.27 with probability 0.1 %); a fix in the wrong
    /// component order scores hundreds. See bingham_filter_surprise().
    double surprise(const Quaternion &measurement, const Distribution &noise) const {
        return surprise_raw(vec(measurement), noise);
    }
    /// surprise() for d = 2 (chi-square with 1 degree of freedom: above 10.83 with 0.1 %).
    double surprise(std::complex<double> measurement, const Distribution &noise) const {
        return surprise_raw(vec(measurement), noise);
    }
    /// update() if the surprise is at most max_surprise (>= 0; INFINITY: no gate), else nothing
    /// changes; a gated-out measurement does not throw. See bingham_filter_update_gated().
    Gated update_gated(const Quaternion &measurement, const Distribution &noise, double max_surprise) {
        return update_gated_raw(vec(measurement), noise, max_surprise);
    }
    /// update_gated() for d = 2.
    Gated update_gated(std::complex<double> measurement, const Distribution &noise, double max_surprise) {
        return update_gated_raw(vec(measurement), noise, max_surprise);
    }

    // World-frame steps (Glover & Kaelbling 2013): `q o r` is the Hamilton product q r ("rotate
    // by r, then by q"); the control and the noises act on the LEFT, in the world frame, where
    // predict_rotation() and update() compose on the right (body frame). The two agree for d = 2
    // and, without a control, for noise isotropic about the identity.

    /// World-frame prediction without a control: x <- w o x, w ~ noise.
    void predict_world(const Distribution &noise) { predict_world_raw(nullptr, noise); }
    /// World-frame prediction x <- w o u o x with a known rotation u (d = 4), applied exactly.
    void predict_world(const Quaternion &u, const Distribution &noise) {
        const std::vector<double> v = vec(u);
        predict_world_raw(&v, noise);
    }
    /// World-frame prediction turning an axis (d = 2) by the unit complex number u.
    void predict_world(std::complex<double> u, const Distribution &noise) {
        const std::vector<double> v = vec(u);
        predict_world_raw(&v, noise);
    }
    /// World-frame update with a measured orientation y = v o x, v ~ noise (d = 4; exact Bayes).
    void update_world(const Quaternion &y, const Distribution &noise) { update_world_raw(vec(y), noise); }
    /// World-frame update with a measured axis (d = 2).
    void update_world(std::complex<double> y, const Distribution &noise) { update_world_raw(vec(y), noise); }
    /// Log predictive density of y = v o x (d = 4; surface measure; the filter is not changed):
    /// what a bank of filters sums, and what picks between the readings of an ambiguous y.
    double log_likelihood_world(const Quaternion &y, const Distribution &noise) const {
        return log_likelihood_world_raw(vec(y), noise);
    }
    /// log_likelihood_world() for d = 2.
    double log_likelihood_world(std::complex<double> y, const Distribution &noise) const {
        return log_likelihood_world_raw(vec(y), noise);
    }

    /// Update with a measured unit direction `body` (sensor frame) of the known unit `reference`
    /// (world frame), von Mises-Fisher concentration `kappa` (d = 4).
    void update_vector(const std::array<double, 3> &body, const std::array<double, 3> &reference, double kappa) {
        require("bingham::Filter::update_vector");
        detail::check(bingham_filter_update_vector(f_, body.data(), reference.data(), kappa));
    }
    /// Log predictive density of a measured direction (d = 4); the filter is not changed.
    double log_likelihood_vector(const std::array<double, 3> &body, const std::array<double, 3> &reference,
                                 double kappa) const {
        require("bingham::Filter::log_likelihood_vector");
        double out = 0;
        detail::check(bingham_filter_log_likelihood_vector(f_, body.data(), reference.data(), kappa, &out));
        return out;
    }

    /// The state (M row-major, z ascending with z[d-1] = 0; the last column of M is the mode).
    Distribution state() const {
        require("bingham::Filter::state");
        Distribution r;
        r.d = d_;
        r.M.resize(d_ * d_);
        r.z.resize(d_);
        detail::check(bingham_filter_get_state(f_, r.M.data(), r.z.data()));
        return r;
    }
    /// Replaces the state (re-initialization); the dimension stays.
    void set_state(const Distribution &s) {
        check_noise(s, "bingham::Filter::set_state");
        detail::check(bingham_filter_set_state(f_, s.M.data(), s.z.data()));
    }
    /// The estimate (the mode, d entries).
    std::vector<double> mode() const {
        require("bingham::Filter::mode");
        std::vector<double> r(d_);
        detail::check(bingham_filter_mode(f_, r.data()));
        return r;
    }
    /// The estimate as a quaternion (d = 4), sign arbitrary (q and -q are the same rotation).
    EstimateQuaternion mode_quaternion() const {
        require("bingham::Filter::mode_quaternion");
        detail::require_dim(d_ == 4, "bingham::Filter::mode_quaternion", "needs a d = 4 filter");
        return Quaternion::from_array(mode().data());
    }
    /// The estimate as a unit complex number (d = 2).
    std::complex<double> mode_complex() const {
        require("bingham::Filter::mode_complex");
        detail::require_dim(d_ == 2, "bingham::Filter::mode_complex", "needs a d = 2 filter");
        const std::vector<double> m = mode();
        return {m[0], m[1]};
    }
    /// The angular spread in radians: per principal direction, the total last.
    std::vector<double> angular_spread() const {
        require("bingham::Filter::angular_spread");
        std::vector<double> s(d_);
        detail::check(bingham_filter_angular_spread(f_, s.data()));
        return s;
    }
    /// The total angular spread in radians (d = 4: ~ the RMS rotation angle from the estimate).
    double uncertainty() const { return angular_spread().back(); }

#if BINGHAM_HPP_EIGEN
    /// update_vector() with Eigen 3-vectors.
    template <class DB, class DR>
    void update_vector(const Eigen::MatrixBase<DB> &body, const Eigen::MatrixBase<DR> &reference, double kappa) {
        update_vector(impl::to_array3(body, "bingham::Filter::update_vector"),
                      impl::to_array3(reference, "bingham::Filter::update_vector"), kappa);
    }
    /// log_likelihood_vector() with Eigen 3-vectors.
    template <class DB, class DR>
    double log_likelihood_vector(const Eigen::MatrixBase<DB> &body, const Eigen::MatrixBase<DR> &reference,
                                 double kappa) const {
        return log_likelihood_vector(impl::to_array3(body, "bingham::Filter::log_likelihood_vector"),
                                     impl::to_array3(reference, "bingham::Filter::log_likelihood_vector"), kappa);
    }
    /// Eigen vectors are refused for measurements and increments at compile time: pass an
    /// Eigen::Quaterniond (d = 4) or std::complex<double> (d = 2). (A Vector4d from
    /// Quaterniond::coeffs() is in (x, y, z, w) order and would be silently wrong.)
    template <class D>
    void update(const Eigen::MatrixBase<D> &, const Distribution &) {
        static_assert(sizeof(D) == 0, "bingham::Filter::update: pass an Eigen::Quaterniond (or bingham::Quaternion), "
                                      "not an Eigen vector: coeffs() is (x, y, z, w), the library is (w, x, y, z)");
    }
    template <class D>
    void predict_rotation(const Eigen::MatrixBase<D> &, const Distribution &) {
        static_assert(sizeof(D) == 0, "bingham::Filter::predict_rotation: pass an Eigen::Quaterniond (or "
                                      "bingham::Quaternion), not an Eigen vector: coeffs() is (x, y, z, w)");
    }
    template <class D>
    void predict_world(const Eigen::MatrixBase<D> &, const Distribution &) {
        static_assert(sizeof(D) == 0, "bingham::Filter::predict_world: pass an Eigen::Quaterniond (or "
                                      "bingham::Quaternion), not an Eigen vector: coeffs() is (x, y, z, w)");
    }
    template <class D>
    void update_world(const Eigen::MatrixBase<D> &, const Distribution &) {
        static_assert(sizeof(D) == 0, "bingham::Filter::update_world: pass an Eigen::Quaterniond (or "
                                      "bingham::Quaternion), not an Eigen vector: coeffs() is (x, y, z, w)");
    }
#endif

private:
    Filter(bingham_filter *f, std::size_t d) : f_(f), d_(d) {}
    void predict_rotation_raw(const std::vector<double> &u, const Distribution &noise) {
        check_noise(noise, "bingham::Filter::predict_rotation");
        detail::require_dim(u.size() == d_, "bingham::Filter::predict_rotation", "u must have d entries");
        detail::check(bingham_filter_predict_rotation(f_, u.data(), noise.M.data(), noise.z.data()));
    }
    void update_raw(const std::vector<double> &measurement, const Distribution &noise) {
        check_noise(noise, "bingham::Filter::update");
        detail::require_dim(measurement.size() == d_, "bingham::Filter::update", "the measurement must have d entries");
        detail::check(bingham_filter_update(f_, measurement.data(), noise.M.data(), noise.z.data()));
    }
    double log_likelihood_raw(const std::vector<double> &measurement, const Distribution &noise) const {
        check_noise(noise, "bingham::Filter::log_likelihood");
        detail::require_dim(measurement.size() == d_, "bingham::Filter::log_likelihood",
                            "the measurement must have d entries");
        double out = 0;
        detail::check(bingham_filter_log_likelihood(f_, measurement.data(), noise.M.data(), noise.z.data(), &out));
        return out;
    }
    double surprise_raw(const std::vector<double> &measurement, const Distribution &noise) const {
        check_noise(noise, "bingham::Filter::surprise");
        detail::require_dim(measurement.size() == d_, "bingham::Filter::surprise", "the measurement must have d entries");
        double out = 0;
        detail::check(bingham_filter_surprise(f_, measurement.data(), noise.M.data(), noise.z.data(), &out));
        return out;
    }
    Gated update_gated_raw(const std::vector<double> &measurement, const Distribution &noise, double max_surprise) {
        check_noise(noise, "bingham::Filter::update_gated");
        detail::require_dim(measurement.size() == d_, "bingham::Filter::update_gated",
                            "the measurement must have d entries");
        double s = 0;
        std::int32_t accepted = 0;
        detail::check(bingham_filter_update_gated(f_, measurement.data(), noise.M.data(), noise.z.data(), max_surprise,
                                                  &s, &accepted));
        return Gated{accepted != 0, s};
    }
    void predict_world_raw(const std::vector<double> *u, const Distribution &noise) {
        check_noise(noise, "bingham::Filter::predict_world");
        detail::require_dim(!u || u->size() == d_, "bingham::Filter::predict_world", "u must have d entries");
        detail::check(bingham_filter_predict_world(f_, u ? u->data() : nullptr, noise.M.data(), noise.z.data()));
    }
    void update_world_raw(const std::vector<double> &y, const Distribution &noise) {
        check_noise(noise, "bingham::Filter::update_world");
        detail::require_dim(y.size() == d_, "bingham::Filter::update_world", "y must have d entries");
        detail::check(bingham_filter_update_world(f_, y.data(), noise.M.data(), noise.z.data()));
    }
    double log_likelihood_world_raw(const std::vector<double> &y, const Distribution &noise) const {
        check_noise(noise, "bingham::Filter::log_likelihood_world");
        detail::require_dim(y.size() == d_, "bingham::Filter::log_likelihood_world", "y must have d entries");
        double out = 0;
        detail::check(bingham_filter_log_likelihood_world(f_, y.data(), noise.M.data(), noise.z.data(), &out));
        return out;
    }
    void require(const char *where) const {
        detail::require(f_ != nullptr, BINGHAM_ERR_NULL_ARGUMENT, where, "empty (moved-from) filter");
    }
    void check_noise(const Distribution &noise, const char *where) const {
        require(where);
        noise.validate(where);
        detail::require_dim(noise.d == d_, where, "the distribution's d differs from the filter's");
    }
    static std::vector<double> vec(const Quaternion &q) { return {q.w, q.x, q.y, q.z}; }
    static std::vector<double> vec(std::complex<double> c) { return {c.real(), c.imag()}; }

    bingham_filter *f_ = nullptr;
    std::size_t d_ = 0;
};

// ---- the spin filter (second-order quaternion Bingham filter) -------------------------------

/// The angular spreads of a SpinFilter (radians; the spin's in radians per step): entries 0-2
/// along the principal directions of the marginal, entry 3 the total (as Filter::angular_spread()).
struct SpinSpread {
    std::array<double, 4> orientation{};
    std::array<double, 4> spin{};
};

/// The second-order quaternion Bingham filter of Glover & Kaelbling (2013): the orientation x and
/// the spin v (the rotation per time step) of an object observed without a gyroscope, e.g. by a
/// camera. Owns a `bingham_spin_filter *`; move-only, copy with clone() (e.g. for a bank of spin
/// hypotheses, compared by their summed log_likelihood()).
///
/// Model (`q o r` = Hamilton product q r, "rotate by r, then by q"; quaternions scalar first):
/// v[n] = w[n] o u[n] o v[n-1], x[n] = v[n-1] o x[n-1], y[n] = o[n] o x[n], with Bingham noises
/// w (process, on the spin; mode at the identity for zero-mean noise) and o (observation), and an
/// optional known change of spin u. The state is the product of two Bingham marginals,
/// orientation() and spin(). Pass the same noise objects every step (the library caches them).
/// A failed call throws Error and leaves the filter unchanged. A moved-from SpinFilter is empty:
/// its methods throw Error(BINGHAM_ERR_NULL_ARGUMENT); destroying or assigning to it is fine.
class SpinFilter {
public:
    /// A filter with the orientation prior `orientation` and the spin prior `spin` (both d = 4).
    /// A uniform orientation prior (z all equal, e.g. 0) means nothing is known; a spin prior
    /// centred on "no spin" has the mode (1, 0, 0, 0).
    SpinFilter(const Distribution &orientation, const Distribution &spin) {
        check4(orientation, "bingham::SpinFilter");
        check4(spin, "bingham::SpinFilter");
        detail::check(bingham_spin_filter_new(orientation.M.data(), orientation.z.data(), spin.M.data(), spin.z.data(),
                                              &f_));
    }
    ~SpinFilter() { bingham_spin_filter_free(f_); }
    SpinFilter(SpinFilter &&o) noexcept : f_(std::exchange(o.f_, nullptr)) {}
    SpinFilter &operator=(SpinFilter &&o) noexcept {
        if (this != &o) {
            bingham_spin_filter_free(f_);
            f_ = std::exchange(o.f_, nullptr);
        }
        return *this;
    }
    SpinFilter(const SpinFilter &) = delete;
    SpinFilter &operator=(const SpinFilter &) = delete;

    /// An independent copy (state and cached noises).
    SpinFilter clone() const {
        require("bingham::SpinFilter::clone");
        bingham_spin_filter *c = nullptr;
        detail::check(bingham_spin_filter_clone(f_, &c));
        return SpinFilter(Adopt{}, c);
    }
    /// False for a moved-from filter.
    explicit operator bool() const noexcept { return f_ != nullptr; }
    /// The C handle (owned by this object).
    bingham_spin_filter *get() noexcept { return f_; }
    const bingham_spin_filter *get() const noexcept { return f_; }

    /// A step without an observation (prediction only): v <- w o v, x <- v o x.
    void step(const Distribution &w) { step_raw(nullptr, w, nullptr, nullptr); }
    /// A step with the observed orientation y = o o x, o ~ `o` (y's sign does not matter).
    void step(const Distribution &w, const Quaternion &y, const Distribution &o) { step_raw(nullptr, w, &y, &o); }
    /// A step with a known change of spin u and no observation: v <- w o u o v, x <- v o x.
    void step(const Quaternion &u, const Distribution &w) { step_raw(&u, w, nullptr, nullptr); }
    /// A step with a known change of spin u and the observed orientation y.
    void step(const Quaternion &u, const Distribution &w, const Quaternion &y, const Distribution &o) {
        step_raw(&u, w, &y, &o);
    }
    /// The log predictive density of observing y = o o x at the step about to be taken (surface
    /// measure on S^3; the filter is not changed). A bank of spin filters sums it over time to
    /// compare its hypotheses; of two readings of an ambiguous observation, the larger wins.
    double log_likelihood(const Quaternion &y, const Distribution &o) const {
        require("bingham::SpinFilter::log_likelihood");
        check4(o, "bingham::SpinFilter::log_likelihood");
        const auto ya = y.array();
        double out = 0;
        detail::check(bingham_spin_filter_log_likelihood(f_, ya.data(), o.M.data(), o.z.data(), &out));
        return out;
    }

    /// The orientation's marginal (M row-major, z ascending with z[3] = 0, mode = last column).
    Distribution orientation() const { return state().first; }
    /// The spin's marginal (the rotation per step).
    Distribution spin() const { return state().second; }
    /// Both marginals (orientation, spin) from one call.
    std::pair<Distribution, Distribution> state() const {
        require("bingham::SpinFilter::state");
        std::pair<Distribution, Distribution> r;
        for (Distribution *b : {&r.first, &r.second}) {
            b->d = 4;
            b->M.resize(16);
            b->z.resize(4);
        }
        detail::check(bingham_spin_filter_get_state(f_, r.first.M.data(), r.first.z.data(), r.second.M.data(),
                                                    r.second.z.data()));
        return r;
    }
    /// Replaces both marginals (re-initialization; the cached noises stay).
    void set_state(const Distribution &orientation, const Distribution &spin) {
        require("bingham::SpinFilter::set_state");
        check4(orientation, "bingham::SpinFilter::set_state");
        check4(spin, "bingham::SpinFilter::set_state");
        detail::check(bingham_spin_filter_set_state(f_, orientation.M.data(), orientation.z.data(), spin.M.data(),
                                                    spin.z.data()));
    }
    /// The orientation estimate (the orientation's mode; sign arbitrary). An Eigen::Quaterniond
    /// where Eigen is enabled (see EstimateQuaternion).
    EstimateQuaternion orientation_mode() const {
        require("bingham::SpinFilter::orientation_mode");
        double q[4];
        detail::check(bingham_spin_filter_orientation_mode(f_, q));
        return Quaternion::from_array(q);
    }
    /// The spin estimate: the most probable rotation per step (its angle / the step's duration
    /// is the angular rate).
    EstimateQuaternion spin_mode() const {
        require("bingham::SpinFilter::spin_mode");
        double q[4];
        detail::check(bingham_spin_filter_spin_mode(f_, q));
        return Quaternion::from_array(q);
    }
    /// The angular spreads of the orientation (rad) and of the spin (rad per step).
    SpinSpread angular_spread() const {
        require("bingham::SpinFilter::angular_spread");
        SpinSpread s;
        detail::check(bingham_spin_filter_angular_spread(f_, s.orientation.data(), s.spin.data()));
        return s;
    }

#if BINGHAM_HPP_EIGEN
    /// Eigen vectors are refused for quaternions at compile time: pass an Eigen::Quaterniond
    /// (coeffs() is (x, y, z, w), the library is (w, x, y, z)).
    template <class D, class... Rest>
    void step(const Eigen::MatrixBase<D> &, const Rest &...) {
        static_assert(sizeof(D) == 0, "bingham::SpinFilter::step: pass an Eigen::Quaterniond (or "
                                      "bingham::Quaternion), not an Eigen vector: coeffs() is (x, y, z, w)");
    }
#endif

private:
    struct Adopt {};
    SpinFilter(Adopt, bingham_spin_filter *f) : f_(f) {}
    void step_raw(const Quaternion *u, const Distribution &w, const Quaternion *y, const Distribution *o) {
        require("bingham::SpinFilter::step");
        check4(w, "bingham::SpinFilter::step");
        if (o) check4(*o, "bingham::SpinFilter::step");
        const std::array<double, 4> ua = u ? u->array() : std::array<double, 4>{},
                                    ya = y ? y->array() : std::array<double, 4>{};
        detail::check(bingham_spin_filter_step(f_, u ? ua.data() : nullptr, w.M.data(), w.z.data(),
                                               y ? ya.data() : nullptr, o ? o->M.data() : nullptr,
                                               o ? o->z.data() : nullptr));
    }
    void require(const char *where) const {
        detail::require(f_ != nullptr, BINGHAM_ERR_NULL_ARGUMENT, where, "empty (moved-from) spin filter");
    }
    static void check4(const Distribution &b, const char *where) {
        b.validate(where);
        detail::require_dim(b.d == 4, where, "needs a d = 4 distribution");
    }
    bingham_spin_filter *f_ = nullptr;
};

// ---- the AHRS --------------------------------------------------------------------------------

/// The AHRS parameters (the C struct; angles rad, times s). Start from ahrs_default_params() or
/// ahrs_params_from_rate(); each field's meaning and default: docs/design.md, "AHRS"
/// ("Parameters").
using AhrsParams = bingham_ahrs_params;

/// The tuned default parameters for the sampling period `sample_time` (seconds: the period, not
/// the rate; 0.01 for 100 Hz). Throws Error(BINGHAM_ERR_INVALID_ARGUMENT) outside 1e-6..1 s
/// (above 1 s the message asks "did you pass a rate in Hz?").
inline AhrsParams ahrs_default_params(double sample_time) {
    AhrsParams p{};
    detail::check(bingham_ahrs_params_default(sample_time, &p));
    return p;
}

/// The tuned default parameters for the sample rate `hz` (samples per second):
/// ahrs_default_params(1.0 / hz). Throws Error(BINGHAM_ERR_INVALID_ARGUMENT) if `hz` is not
/// finite, not > 0, below 1 Hz or above 1e6 Hz.
inline AhrsParams ahrs_params_from_rate(double hz) {
    AhrsParams p{};
    detail::check(bingham_ahrs_params_from_rate(hz, &p));
    return p;
}

/// An IMU attitude and heading reference system on the Bingham filter. Owns a `bingham_ahrs *`;
/// move-only, copy with clone(). The orientation maps sensor to world ENU (x east, y north,
/// z up); gyroscope rad/s, accelerometer m/s^2 (+g up at rest), magnetometer any unit.
/// A moved-from Ahrs is empty: its methods throw Error(BINGHAM_ERR_NULL_ARGUMENT).
/// Contract: docs/guide.md, "IMU orientation (AHRS)"; design and parameters: docs/design.md,
/// "AHRS".
class Ahrs {
public:
    /// With the default parameters for the sampling period `sample_time` (s: the period, not the
    /// rate; `Ahrs(0.01)` or `Ahrs::from_rate(100)` for 100 Hz).
    explicit Ahrs(double sample_time) : Ahrs(ahrs_default_params(sample_time)) {}
    /// With the default parameters for the sample rate `hz` (samples per second, 1 to 1e6 Hz):
    /// `Ahrs::from_rate(100)` is `Ahrs(0.01)`. Throws as ahrs_params_from_rate().
    static Ahrs from_rate(double hz) { return Ahrs(ahrs_params_from_rate(hz)); }
    /// With the given parameters (validated by the library; the message names a bad field).
    explicit Ahrs(const AhrsParams &params) { detail::check(bingham_ahrs_new(&params, &a_)); }
    ~Ahrs() { bingham_ahrs_free(a_); }
    Ahrs(Ahrs &&o) noexcept : a_(std::exchange(o.a_, nullptr)) {}
    Ahrs &operator=(Ahrs &&o) noexcept {
        if (this != &o) {
            bingham_ahrs_free(a_);
            a_ = std::exchange(o.a_, nullptr);
        }
        return *this;
    }
    Ahrs(const Ahrs &) = delete;
    Ahrs &operator=(const Ahrs &) = delete;

    /// An independent copy (state, bias, disturbance tracking).
    Ahrs clone() const {
        require("bingham::Ahrs::clone");
        bingham_ahrs *c = nullptr;
        detail::check(bingham_ahrs_clone(a_, &c));
        return Ahrs(Adopt{}, c);
    }
    explicit operator bool() const noexcept { return a_ != nullptr; }
    bingham_ahrs *get() noexcept { return a_; }
    const bingham_ahrs *get() const noexcept { return a_; }

    /// One sample without magnetometer (6-D: heading unobserved), taken sample_time after the
    /// previous one. A NaN/Inf entry means "no sample" of that sensor (the gyroscope's a gap the
    /// AHRS carries the orientation through, widening the spread); throws for a gyroscope turning
    /// by more than 1e6 rad in the sample, or a first sample without a finite accelerometer.
    void update(const std::array<double, 3> &gyr, const std::array<double, 3> &acc) {
        require("bingham::Ahrs::update");
        detail::check(bingham_ahrs_update(a_, gyr.data(), acc.data(), nullptr));
    }
    /// One sample with magnetometer (as above).
    void update(const std::array<double, 3> &gyr, const std::array<double, 3> &acc, const std::array<double, 3> &mag) {
        require("bingham::Ahrs::update");
        detail::check(bingham_ahrs_update(a_, gyr.data(), acc.data(), mag.data()));
    }
    /// One sample without magnetometer taken `dt` seconds after the previous one (its own time
    /// step: jitter, dropped packets; bingham_ahrs_update_dt()); otherwise as update().
    /// update_dt(sample_time, ...) is update(...), bit for bit. Throws
    /// Error(BINGHAM_ERR_INVALID_ARGUMENT) for `dt` not finite or outside
    /// BINGHAM_AHRS_MIN_SAMPLE_TIME .. BINGHAM_AHRS_MAX_STEP_TIME (1e-6 .. 10 s), the AHRS unchanged.
    void update_dt(double dt, const std::array<double, 3> &gyr, const std::array<double, 3> &acc) {
        require("bingham::Ahrs::update_dt");
        detail::check(bingham_ahrs_update_dt(a_, dt, gyr.data(), acc.data(), nullptr));
    }
    /// One sample with magnetometer taken `dt` seconds after the previous one (as above).
    void update_dt(double dt, const std::array<double, 3> &gyr, const std::array<double, 3> &acc,
                   const std::array<double, 3> &mag) {
        require("bingham::Ahrs::update_dt");
        detail::check(bingham_ahrs_update_dt(a_, dt, gyr.data(), acc.data(), mag.data()));
    }
    /// n samples (gyr, acc, mag: n x 3 row-major; mag empty for none): returns the n x 4
    /// quaternions (w, x, y, z per row). A row holding NaN is "no sample" of that sensor. A
    /// refused sample throws (the message names it, "sample k: ..."); the samples before it
    /// have been processed (as in the C API).
    std::vector<double> update_batch(const std::vector<double> &gyr, const std::vector<double> &acc,
                                     const std::vector<double> &mag = {}) {
        require("bingham::Ahrs::update_batch");
        const std::size_t n = gyr.size() / 3;
        detail::require_dim(gyr.size() == 3 * n && acc.size() == 3 * n && (mag.empty() || mag.size() == 3 * n),
                            "bingham::Ahrs::update_batch", "gyr, acc (and mag) must all be n x 3");
        std::vector<double> q(4 * n);
        if (n == 0) return q;
        detail::check(
            bingham_ahrs_update_batch(a_, n, gyr.data(), acc.data(), mag.empty() ? nullptr : mag.data(), q.data()));
        return q;
    }
    /// n samples with their timestamps `t` (n values, seconds, strictly increasing, any origin;
    /// bingham_ahrs_update_batch_timed()): sample k's time step is t[k] - t[k-1], the first
    /// one's from the last timestamp of the previous timed batch (or sample_time if there was
    /// none, or an untimed update came since); gyr, acc, mag (empty for none) n x 3 row-major as
    /// in update_batch(). Returns the n x 4 quaternions. With uniformly spaced timestamps it is
    /// update_batch() bit for bit; a batch may be split anywhere. A timestamp not finite or not
    /// after the previous one, a step above 10 s or a refused sample throws (message "sample k:
    /// ..."); the samples before it have been processed.
    std::vector<double> update_batch(const std::vector<double> &t, const std::vector<double> &gyr,
                                     const std::vector<double> &acc, const std::vector<double> &mag) {
        require("bingham::Ahrs::update_batch");
        const std::size_t n = t.size();
        detail::require_dim(gyr.size() == 3 * n && acc.size() == 3 * n && (mag.empty() || mag.size() == 3 * n),
                            "bingham::Ahrs::update_batch", "t has n entries; gyr, acc (and mag) must all be n x 3");
        std::vector<double> q(4 * n);
        if (n == 0) return q;
        detail::check(bingham_ahrs_update_batch_timed(a_, n, t.data(), gyr.data(), acc.data(),
                                                      mag.empty() ? nullptr : mag.data(), q.data(), nullptr, nullptr));
        return q;
    }
#if BINGHAM_HPP_EIGEN
    /// n samples as Eigen matrices (gyr, acc, mag: n x 3, any storage order; an empty (0-row)
    /// mag for none): returns the n x 4 quaternions (w, x, y, z per row). With `spread` non-null
    /// it receives the n total angular spreads (rad, as uncertainty()) after each sample, with
    /// `health` non-null the n health scores (health().score) after each sample. A refused
    /// sample throws; the samples before it have been processed.
    template <class G, class A, class M>
    Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> update_batch(
        const Eigen::MatrixBase<G> &gyr, const Eigen::MatrixBase<A> &acc, const Eigen::MatrixBase<M> &mag,
        Eigen::VectorXd *spread = nullptr, Eigen::VectorXd *health = nullptr) {
        require("bingham::Ahrs::update_batch");
        const Eigen::Index n = gyr.rows();
        detail::require_dim(gyr.cols() == 3 && acc.cols() == 3 && acc.rows() == n &&
                                (mag.rows() == 0 || (mag.rows() == n && mag.cols() == 3)),
                            "bingham::Ahrs::update_batch", "gyr, acc (and mag) must all be n x 3");
        using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
        const Rows3 g = gyr, a = acc, m = mag;
        Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> q(n, 4);
        if (spread) spread->resize(n);
        if (health) health->resize(n);
        if (n == 0) return q;
        const double *mp = mag.rows() == 0 ? nullptr : m.data();
        detail::check(bingham_ahrs_update_batch_health(a_, static_cast<std::size_t>(n), g.data(), a.data(), mp,
                                                       q.data(), spread ? spread->data() : nullptr,
                                                       health ? health->data() : nullptr));
        return q;
    }
    /// As above without a magnetometer.
    template <class G, class A>
    Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> update_batch(
        const Eigen::MatrixBase<G> &gyr, const Eigen::MatrixBase<A> &acc, Eigen::VectorXd *spread = nullptr,
        Eigen::VectorXd *health = nullptr) {
        return update_batch(gyr, acc, Eigen::Matrix<double, 0, 3>(), spread, health);
    }
    /// n samples with their timestamps `t` (an Eigen vector of n seconds, row or column,
    /// strictly increasing; bingham_ahrs_update_batch_timed(), see the std::vector overload):
    /// gyr, acc, mag as above (mag with 0 rows for none), `spread` and `health` as above.
    template <class T, class G, class A, class M>
    Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> update_batch(
        const Eigen::MatrixBase<T> &t, const Eigen::MatrixBase<G> &gyr, const Eigen::MatrixBase<A> &acc,
        const Eigen::MatrixBase<M> &mag, Eigen::VectorXd *spread = nullptr, Eigen::VectorXd *health = nullptr) {
        require("bingham::Ahrs::update_batch");
        const Eigen::Index n = gyr.rows();
        detail::require_dim((t.rows() == 1 || t.cols() == 1 || t.size() == 0) && t.size() == n && gyr.cols() == 3 &&
                                acc.cols() == 3 && acc.rows() == n &&
                                (mag.rows() == 0 || (mag.rows() == n && mag.cols() == 3)),
                            "bingham::Ahrs::update_batch", "t has n entries; gyr, acc (and mag) must all be n x 3");
        using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
        const Rows3 g = gyr, a = acc, m = mag;
        Eigen::VectorXd tv(n);
        for (Eigen::Index k = 0; k < n; ++k) tv(k) = t.cols() == 1 ? t(k, 0) : t(0, k);
        Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> q(n, 4);
        if (spread) spread->resize(n);
        if (health) health->resize(n);
        if (n == 0) return q;
        const double *mp = mag.rows() == 0 ? nullptr : m.data();
        detail::check(bingham_ahrs_update_batch_timed(a_, static_cast<std::size_t>(n), tv.data(), g.data(), a.data(),
                                                      mp, q.data(), spread ? spread->data() : nullptr,
                                                      health ? health->data() : nullptr));
        return q;
    }
#endif
    /// The orientation estimate (sensor -> world ENU, w >= 0); an Eigen::Quaterniond where Eigen
    /// is enabled (see EstimateQuaternion).
    EstimateQuaternion quaternion() const {
        require("bingham::Ahrs::quaternion");
        double q[4];
        detail::check(bingham_ahrs_quaternion(a_, q));
        return Quaternion::from_array(q);
    }
    /// The Bingham state of the orientation (d = 4).
    Distribution state() const {
        require("bingham::Ahrs::state");
        Distribution r;
        r.d = 4;
        r.M.resize(16);
        r.z.resize(4);
        detail::check(bingham_ahrs_state(a_, r.M.data(), r.z.data()));
        return r;
    }
    /// Replaces the orientation estimate (bias and low-pass filters are kept).
    void set_state(const Distribution &s) {
        require("bingham::Ahrs::set_state");
        s.validate("bingham::Ahrs::set_state");
        detail::require_dim(s.d == 4, "bingham::Ahrs::set_state", "needs d = 4");
        detail::check(bingham_ahrs_set_state(a_, s.M.data(), s.z.data()));
    }
    /// The angular spread (rad): three principal directions, then the total.
    std::array<double, 4> angular_spread() const {
        require("bingham::Ahrs::angular_spread");
        std::array<double, 4> s{};
        detail::check(bingham_ahrs_angular_spread(a_, s.data()));
        return s;
    }
    /// The total angular spread (rad), ~ the RMS orientation error when calibrated.
    double uncertainty() const { return angular_spread()[3]; }
    /// The health readout (bingham_ahrs_health()): `score` about 1 when the sensors agree with
    /// the model, above BINGHAM_AHRS_HEALTH_THRESHOLD (10) an input mistake is likely (gyroscope
    /// in deg/s, wrong sample time); `mag_rejected` near 1: magnetometer disturbed or axes wrong;
    /// `mag_dip` (rad, positive below the horizon) of the wrong sign for the place: a flipped
    /// accelerometer; `gyr_missing_time`, `acc_missing_time`, `mag_missing_time`: seconds since
    /// each sensor's last usable sample (0 right after one).
    bingham_ahrs_health_report health() const {
        require("bingham::Ahrs::health");
        bingham_ahrs_health_report h{};
        detail::check(bingham_ahrs_health(a_, &h));
        return h;
    }
    /// The gyroscope bias estimate (rad/s, sensor frame).
    std::array<double, 3> gyro_bias() const {
        require("bingham::Ahrs::gyro_bias");
        std::array<double, 3> b{};
        detail::check(bingham_ahrs_gyro_bias(a_, b.data()));
        return b;
    }
    /// The gyroscope scale-error estimate (relative, per sensor axis: the gyroscope reads
    /// (1 + s_i) times the rate about axis i, plus the bias); zeros when gyro_scale_std is 0.
    std::array<double, 3> gyro_scale() const {
        require("bingham::Ahrs::gyro_scale");
        std::array<double, 3> s{};
        detail::check(bingham_ahrs_gyro_scale(a_, s.data()));
        return s;
    }
    /// The covariance of the gyroscope bias estimate ((rad/s)^2, sensor frame): 3 x 3 ROW-MAJOR,
    /// symmetric positive semi-definite; bias_std^2 * I on creation.
    std::array<double, 9> gyro_bias_covariance() const {
        require("bingham::Ahrs::gyro_bias_covariance");
        std::array<double, 9> c{};
        detail::check(bingham_ahrs_gyro_bias_covariance(a_, c.data()));
        return c;
    }
    /// The covariance of the orientation error (rad^2): 3 x 3 ROW-MAJOR, the error as a rotation
    /// vector phi in the WORLD frame (ENU: x east, y north, z up), q_true = exp(phi/2) * q_est
    /// with q_est = quaternion(); what sensor_msgs/Imu.orientation_covariance holds (row-major
    /// there too). Symmetric positive semi-definite, its trace uncertainty()^2; the identity
    /// before the first sample.
    std::array<double, 9> orientation_covariance() const {
        require("bingham::Ahrs::orientation_covariance");
        std::array<double, 9> c{};
        detail::check(bingham_ahrs_orientation_covariance(a_, c.data()));
        return c;
    }
    /// The online estimate of the magnetometer's latency behind the gyroscope (s), or nullopt
    /// while there is none yet (BINGHAM_ERR_NOT_CONVERGED: less than 5 s of informative motion).
    /// The default parameters (mag_latency = BINGHAM_AHRS_LATENCY_ESTIMATE) compensate it.
    std::optional<double> mag_latency_estimate() const {
        require("bingham::Ahrs::mag_latency_estimate");
        double l = 0.0;
        const bingham_status st = bingham_ahrs_mag_latency_estimate(a_, &l);
        if (st == BINGHAM_ERR_NOT_CONVERGED) {
            (void)last_error_message();  // handled here: read, so it is not reported as unread later
            return std::nullopt;
        }
        detail::check(st);
        return l;
    }

#if BINGHAM_HPP_EIGEN
    /// update() with Eigen 3-vectors.
    template <class DG, class DA>
    void update(const Eigen::MatrixBase<DG> &gyr, const Eigen::MatrixBase<DA> &acc) {
        update(impl::to_array3(gyr, "bingham::Ahrs::update"), impl::to_array3(acc, "bingham::Ahrs::update"));
    }
    template <class DG, class DA, class DM>
    void update(const Eigen::MatrixBase<DG> &gyr, const Eigen::MatrixBase<DA> &acc, const Eigen::MatrixBase<DM> &mag) {
        update(impl::to_array3(gyr, "bingham::Ahrs::update"), impl::to_array3(acc, "bingham::Ahrs::update"),
               impl::to_array3(mag, "bingham::Ahrs::update"));
    }
    /// update_dt() with Eigen 3-vectors.
    template <class DG, class DA>
    void update_dt(double dt, const Eigen::MatrixBase<DG> &gyr, const Eigen::MatrixBase<DA> &acc) {
        update_dt(dt, impl::to_array3(gyr, "bingham::Ahrs::update_dt"), impl::to_array3(acc, "bingham::Ahrs::update_dt"));
    }
    template <class DG, class DA, class DM>
    void update_dt(double dt, const Eigen::MatrixBase<DG> &gyr, const Eigen::MatrixBase<DA> &acc,
                   const Eigen::MatrixBase<DM> &mag) {
        update_dt(dt, impl::to_array3(gyr, "bingham::Ahrs::update_dt"), impl::to_array3(acc, "bingham::Ahrs::update_dt"),
                  impl::to_array3(mag, "bingham::Ahrs::update_dt"));
    }
    /// The gyroscope bias as an Eigen vector.
    Eigen::Vector3d gyro_bias_vector() const {
        const auto b = gyro_bias();
        return {b[0], b[1], b[2]};
    }
    /// The gyroscope scale-error estimate as an Eigen vector (relative, per sensor axis).
    Eigen::Vector3d gyro_scale_vector() const {
        const auto s = gyro_scale();
        return {s[0], s[1], s[2]};
    }
    /// The covariance of the gyroscope bias estimate as an Eigen matrix ((rad/s)^2).
    Eigen::Matrix3d gyro_bias_covariance_matrix() const {
        const auto c = gyro_bias_covariance();
        Eigen::Matrix3d m;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) m(i, j) = c[static_cast<std::size_t>(3 * i + j)];
        return m;
    }
    /// The orientation covariance (orientation_covariance()) as an Eigen matrix (rad^2, world
    /// frame): entry (i, j) is the row-major array's [3 i + j].
    Eigen::Matrix3d orientation_covariance_matrix() const {
        const auto c = orientation_covariance();
        Eigen::Matrix3d m;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) m(i, j) = c[static_cast<std::size_t>(3 * i + j)];
        return m;
    }
#endif

private:
    struct Adopt {};
    Ahrs(Adopt, bingham_ahrs *a) : a_(a) {}
    void require(const char *where) const {
        detail::require(a_ != nullptr, BINGHAM_ERR_NULL_ARGUMENT, where, "empty (moved-from) AHRS");
    }
    bingham_ahrs *a_ = nullptr;
};

/// What smooth_ex() returns: per sample the smoothed quaternion (n x 4, w, x, y, z), the total
/// angular spread (n, rad), the smoothed gyroscope bias (n x 3, rad/s) and the orientation
/// covariance (n x 9, rad², row-major 3 x 3 per sample), all row-major.
struct Smoothed {
    std::vector<double> quat, spread, bias, covariance;
};

/// The offline smoother over a whole recording (bingham_ahrs_smooth()): gyr, acc, mag (empty
/// for none) n x 3 row-major, row k the sample at k * sample_time (a row holding NaN: no sample
/// of that sensor). Returns the n x 4 smoothed quaternions (w, x, y, z per row, sensor -> world
/// ENU). Throws bingham::Error as the C call fails (nothing is returned then).
inline std::vector<double> smooth(const AhrsParams &params, const std::vector<double> &gyr,
                                  const std::vector<double> &acc, const std::vector<double> &mag = {}) {
    const std::size_t n = gyr.size() / 3;
    detail::require_dim(gyr.size() == 3 * n && acc.size() == 3 * n && (mag.empty() || mag.size() == 3 * n),
                        "bingham::smooth", "gyr, acc (and mag) must all be n x 3");
    std::vector<double> q(4 * n);
    if (n == 0) return q;
    detail::check(
        bingham_ahrs_smooth(&params, n, gyr.data(), acc.data(), mag.empty() ? nullptr : mag.data(), q.data(), nullptr));
    return q;
}

/// smooth() with every output and optional timestamps `t` (empty: uniformly spaced by
/// sample_time; else n values, seconds, strictly increasing; bingham_ahrs_smooth_ex()).
inline Smoothed smooth_ex(const AhrsParams &params, const std::vector<double> &t, const std::vector<double> &gyr,
                          const std::vector<double> &acc, const std::vector<double> &mag = {}) {
    const std::size_t n = gyr.size() / 3;
    detail::require_dim(gyr.size() == 3 * n && acc.size() == 3 * n && (mag.empty() || mag.size() == 3 * n) &&
                            (t.empty() || t.size() == n),
                        "bingham::smooth_ex", "gyr, acc (and mag) must all be n x 3, t empty or n");
    Smoothed r{std::vector<double>(4 * n), std::vector<double>(n), std::vector<double>(3 * n),
               std::vector<double>(9 * n)};
    if (n == 0) return r;
    detail::check(bingham_ahrs_smooth_ex(&params, n, t.empty() ? nullptr : t.data(), gyr.data(), acc.data(),
                                         mag.empty() ? nullptr : mag.data(), r.quat.data(), r.spread.data(),
                                         r.bias.data(), r.covariance.data()));
    return r;
}

#if BINGHAM_HPP_EIGEN
/// smooth() on Eigen matrices (gyr, acc, mag: n x 3, any storage order; mag with 0 rows for
/// none): returns the n x 4 smoothed quaternions (w, x, y, z per row); with `spread` non-null it
/// receives the n total angular spreads (rad).
template <class G, class A, class M>
Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> smooth(const AhrsParams &params,
                                                                  const Eigen::MatrixBase<G> &gyr,
                                                                  const Eigen::MatrixBase<A> &acc,
                                                                  const Eigen::MatrixBase<M> &mag,
                                                                  Eigen::VectorXd *spread = nullptr) {
    const Eigen::Index n = gyr.rows();
    detail::require_dim(gyr.cols() == 3 && acc.cols() == 3 && acc.rows() == n &&
                            (mag.rows() == 0 || (mag.rows() == n && mag.cols() == 3)),
                        "bingham::smooth", "gyr, acc (and mag) must all be n x 3");
    using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
    const Rows3 g = gyr, a = acc, m = mag;
    Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> q(n, 4);
    if (spread) spread->resize(n);
    if (n == 0) return q;
    detail::check(bingham_ahrs_smooth(&params, static_cast<std::size_t>(n), g.data(), a.data(),
                                      mag.rows() == 0 ? nullptr : m.data(), q.data(),
                                      spread ? spread->data() : nullptr));
    return q;
}
#endif

}  // inline namespace
}  // namespace bingham

#endif  // BINGHAM_HPP
