// The vector observation, rotation noise and angular spread functions (and their filter
// counterparts) against references computed here with Eigen, independently of the library:
//
// - bingham_vector_observation: the Bingham exponent of the result, q^T M Z M^T q - max z,
//   equals kappa r^T R(q) b - kappa for random unit b, r and quaternions q, with R(q) from
//   Eigen::Quaterniond(w, x, y, z).toRotationMatrix(); z = (-2k, -2k, 0, 0); M orthogonal; the
//   mode columns rotate b onto r.
// - bingham_filter_update_vector on a d = 4 filter: the posterior exponent M Z M^T equals that of
//   bingham_multiply(state, observation).
// - bingham_noise_from_angle_std: bingham_second_moment of the result against composite Simpson
//   quadrature of the generating distribution: d = 4, rotation vector v ~ N(0, s^2 I3),
//   q = (cos(|v|/2), sin(|v|/2) v/|v|), E[q q^T] = diag(c, (1-c)/3, (1-c)/3, (1-c)/3) with
//   c = E[cos^2(|v|/2)] over the chi-3 radial density; d = 2, a ~ N(0, s^2), E[x x^T] =
//   diag(E[cos^2 a], E[sin^2 a]).
// - bingham_angular_spread / bingham_filter_angular_spread: from the second moment (library, and
//   brute-force sphere quadrature of exp(x^T A x)), eigen-decomposed by Eigen: per-axis k sqrt(w_i)
//   (ascending), total k sqrt(1 - m^T S m) with m the mode; k = 2 (d = 4), 1 (d = 2).
// - bingham_filter_log_likelihood_vector: log of the brute-force integral over S^3 of
//   f_state(q) kappa / (4 pi sinh kappa) exp(kappa r^T R(q) b), f_state from bingham_pdf (at the
//   mode, times exp of the exponent difference; its integral over S^3 is checked to be 1).
#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "check.h"
#include "eigen_util.hpp"
#include "sphere_quadrature.hpp"

using Eigen::Matrix3d;
using Eigen::Matrix4d;
using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::Vector4d;
using Eigen::VectorXd;
using namespace eigen_util;

static std::mt19937_64 rng(20240611);

static const std::vector<Node> &nodes4() {
    static std::vector<Node> n = sphere_nodes(4, 80);  // 80 x 80 x 160
    return n;
}

static MatrixXd exponent(const MatrixXd &m, const VectorXd &z) { return m * z.asDiagonal() * m.transpose(); }


// R(q) for q = (w, x, y, z): Eigen's constructor is scalar first (its coeffs() are not).
static Matrix3d rotation(const VectorXd &q) {
    return Eigen::Quaterniond(q(0), q(1), q(2), q(3)).normalized().toRotationMatrix();
}

// ---- (a) the observation's exponent ---------------------------------------------------------

static void test_vector_observation() {
    const double kappas[] = {0.0, 1e-3, 0.7, 5.0, 120.0, 3e4};
    int worst_fail = 0;
    for (double kappa : kappas)
        for (int rep = 0; rep < 8; ++rep) {
            VectorXd b = random_unit(rng, 3), r = random_unit(rng, 3);
            if (rep == 0) r = b;          // aligned
            if (rep == 1) r = -b;         // opposite
            double m[16], z[4];
            CHECK_OK(bingham_vector_observation(b.data(), r.data(), kappa, m, z));
            CHECK(z[0] == -2 * kappa && z[1] == -2 * kappa && z[2] == 0 && z[3] == 0);
            MatrixXd M = from_row_major(m, 4);
            CHECK(max_abs(M.transpose() * M - MatrixXd::Identity(4, 4)) < 1e-14);
            VectorXd zv = Eigen::Map<VectorXd>(z, 4);
            MatrixXd A = exponent(M, zv);
            double top = zv.maxCoeff();
            double scale = std::max(1.0, kappa);
            for (int k = 0; k < 50; ++k) {
                VectorXd q = random_unit(rng, 4);
                double lhs = quad_form(A, q) - top;
                double rhs = kappa * r.dot(rotation(q) * b) - kappa;
                if (std::fabs(lhs - rhs) > 1e-12 * scale) ++worst_fail;
            }
            // the mode columns (z = 0) are rotations taking b onto r
            if (kappa > 0)
                for (int c = 2; c < 4; ++c) {
                    VectorXd q = M.col(c);
                    CHECK((rotation(q) * b - r).norm() < 1e-13);
                }
        }
    CHECK(worst_fail == 0);
    if (worst_fail) fprintf(stderr, "    vector_observation: %d exponent mismatches\n", worst_fail);
}

// ---- (b) filter update with a vector = multiply ----------------------------------------------

static void test_update_vector() {
    for (int rep = 0; rep < 12; ++rep) {
        MatrixXd m0 = random_orthogonal(rng, 4);
        VectorXd z0 = random_z(rng, 4, -40, 0), b = random_unit(rng, 3), r = random_unit(rng, 3);
        double kappa = std::pow(10.0, std::uniform_real_distribution<double>(-2, 4)(rng));
        std::vector<double> m0r = row_major(m0);
        bingham_filter *f = NULL;
        CHECK_OK(bingham_filter_new(4, m0r.data(), z0.data(), &f));
        if (!f) return;
        double ms[16], zs[4], mo[16], zo[4], mp[16], zp[4], mf[16], zf[4];
        CHECK_OK(bingham_filter_get_state(f, ms, zs));
        CHECK_OK(bingham_vector_observation(b.data(), r.data(), kappa, mo, zo));
        CHECK_OK(bingham_multiply(4, ms, zs, mo, zo, mp, zp));
        CHECK_OK(bingham_filter_update_vector(f, b.data(), r.data(), kappa));
        CHECK_OK(bingham_filter_get_state(f, mf, zf));
        VectorXd zpv = Eigen::Map<VectorXd>(zp, 4), zfv = Eigen::Map<VectorXd>(zf, 4);
        MatrixXd Ap = exponent(from_row_major(mp, 4), zpv), Af = exponent(from_row_major(mf, 4), zfv);
        double scale = std::max(1.0, zpv.cwiseAbs().maxCoeff());
        CHECK(max_abs(Ap - Af) < 1e-12 * scale);
        CHECK(max_abs(zpv - zfv) < 1e-12 * scale);
        // and against a from-scratch exponent: state + observation, eigen-shifted
        MatrixXd Aref = exponent(m0, z0) + exponent(from_row_major(mo, 4), Eigen::Map<VectorXd>(zo, 4));
        Eigen::SelfAdjointEigenSolver<MatrixXd> es(Aref);
        VectorXd lam = es.eigenvalues().array() - es.eigenvalues()(3);
        CHECK(max_abs(zfv - lam) < 1e-11 * scale);
        bingham_filter_free(f);
    }
}

// ---- (c) rotation noise from an angle std ----------------------------------------------------

// Composite Simpson of g on [a, b] with n (even) intervals.
template <class F>
static double simpson(F g, double a, double b, int n) {
    double h = (b - a) / n, s = g(a) + g(b);
    for (int i = 1; i < n; ++i) s += (i % 2 ? 4.0 : 2.0) * g(a + i * h);
    return s * h / 3.0;
}

static void test_noise_from_angle_std() {
    const double sigmas[] = {1e-3, 0.01, 0.05, 0.2, 0.5, 1.0, 1.7, 3.0};
    for (double s : sigmas) {
        // d = 4: chi-3 radial density of |v|: sqrt(2/pi) t^2 / s^3 exp(-t^2 / (2 s^2))
        auto chi3 = [s](double t) { return std::sqrt(2 / PI) * t * t / (s * s * s) * std::exp(-t * t / (2 * s * s)); };
        double mass = simpson(chi3, 0, 12 * s, 20000);
        double c = simpson([&](double t) { double h = std::cos(t / 2); return chi3(t) * h * h; }, 0, 12 * s, 20000);
        CHECK_CLOSE(mass, 1.0, 1e-12);
        double m[16], z[4], S[16];
        CHECK_OK(bingham_noise_from_angle_std(4, s, m, z));
        CHECK(m[0 * 4 + 3] == 1.0 && m[1 * 4 + 3] == 0.0 && m[2 * 4 + 3] == 0.0 && m[3 * 4 + 3] == 0.0);
        CHECK(z[0] <= z[1] && z[1] <= z[2] && z[3] == 0.0);
        CHECK_OK(bingham_second_moment(4, m, z, S));
        Matrix4d ref = Matrix4d::Zero();
        ref(0, 0) = c;
        for (int i = 1; i < 4; ++i) ref(i, i) = (1 - c) / 3;
        double err = max_abs(from_row_major(S, 4) - ref);
        CHECK(err < 1e-9);
        if (!(err < 1e-9)) fprintf(stderr, "    noise d=4 sigma=%g: |S - S_ref| = %.3g\n", s, err);
        // small sigma: z ~ -2/s^2
        if (s <= 0.01) CHECK(std::fabs(z[0] * s * s / 2 + 1) < 0.01);

        // d = 2: a ~ N(0, s^2)
        auto gauss = [s](double a) { return std::exp(-a * a / (2 * s * s)) / (std::sqrt(2 * PI) * s); };
        double c2 = simpson([&](double a) { double h = std::cos(a); return gauss(a) * h * h; }, -12 * s, 12 * s, 40000);
        double m2[4], z2[2], S2[4];
        CHECK_OK(bingham_noise_from_angle_std(2, s, m2, z2));
        CHECK(m2[0 * 2 + 1] == 1.0 && m2[1 * 2 + 1] == 0.0 && z2[1] == 0.0 && z2[0] <= 0.0);
        CHECK_OK(bingham_second_moment(2, m2, z2, S2));
        MatrixXd ref2 = MatrixXd::Zero(2, 2);
        ref2(0, 0) = c2;
        ref2(1, 1) = 1 - c2;
        double err2 = max_abs(from_row_major(S2, 2) - ref2);
        CHECK(err2 < 1e-9);
        if (!(err2 < 1e-9)) fprintf(stderr, "    noise d=2 sigma=%g: |S - S_ref| = %.3g\n", s, err2);
        if (s <= 0.01) CHECK(std::fabs(z2[0] * 2 * s * s + 1) < 0.01);
    }
}

// ---- (d) angular spread ------------------------------------------------------------------------

// The spread k sqrt(w_i) (ascending), total k sqrt(1 - m^T S m), from a second moment S.
static VectorXd spread_from_moment(const MatrixXd &S) {
    int d = (int)S.rows();
    double k = d == 4 ? 2.0 : 1.0;
    Eigen::SelfAdjointEigenSolver<MatrixXd> es(S);
    VectorXd w = es.eigenvalues(), out(d);
    VectorXd mode = es.eigenvectors().col(d - 1);
    for (int i = 0; i + 1 < d; ++i) out(i) = k * std::sqrt(std::max(0.0, w(i)));
    out(d - 1) = k * std::sqrt(std::max(0.0, 1 - quad_form(S, mode)));
    return out;
}

// E[x x^T] of the density prop. to exp(x^T A x) on S^3, by quadrature.
static MatrixXd quadrature_moment4(const MatrixXd &A) {
    double top = Eigen::SelfAdjointEigenSolver<MatrixXd>(A).eigenvalues().maxCoeff(), F = 0;
    MatrixXd S = MatrixXd::Zero(4, 4);
    for (const Node &nd : nodes4()) {
        double e = nd.w * std::exp(quad_form(A, nd.x) - top);
        F += e;
        add_outer(S, e, nd.x);
    }
    return S / F;
}

static void test_angular_spread() {
    for (int d = 2; d <= 4; d += 2)
        for (int rep = 0; rep < 10; ++rep) {
            MatrixXd m = random_orthogonal(rng, d);
            VectorXd z = random_z(rng, d, rep < 5 ? -20 : -3000, 0);
            std::vector<double> mr = row_major(m), S(d * d), sp(d);
            CHECK_OK(bingham_second_moment(d, mr.data(), z.data(), S.data()));
            CHECK_OK(bingham_angular_spread(d, mr.data(), z.data(), sp.data()));
            VectorXd ref = spread_from_moment(from_row_major(S.data(), d));
            VectorXd got = Eigen::Map<VectorXd>(sp.data(), d);
            CHECK(max_abs(got - ref) < 1e-10);
            double sq = 0;
            for (int i = 0; i + 1 < d; ++i) sq += got(i) * got(i);
            CHECK_CLOSE(sq, got(d - 1) * got(d - 1), 1e-12);
            // independent of the library's moments: quadrature (moderate z only)
            if (d == 4 && rep < 3) {
                VectorXd q = spread_from_moment(quadrature_moment4(exponent(m, z)));
                CHECK(max_abs(got - q) < 1e-9);
                if (!(max_abs(got - q) < 1e-9)) fprintf(stderr, "    spread vs quadrature: %.3g\n", max_abs(got - q));
            }
            // the filter's readout of the same distribution
            bingham_filter *f = NULL;
            CHECK_OK(bingham_filter_new((size_t)d, mr.data(), z.data(), &f));
            if (!f) continue;
            std::vector<double> fs(d);
            CHECK_OK(bingham_filter_angular_spread(f, fs.data()));
            CHECK(max_abs(Eigen::Map<VectorXd>(fs.data(), d) - ref) < 1e-10);
            bingham_filter_free(f);
        }
    // a distribution with RMS angle 5 degrees reads about 5 degrees
    double m[16], z[4], sp[4];
    double s = 5.0 * PI / 180.0 / std::sqrt(3.0);  // per axis
    CHECK_OK(bingham_noise_from_angle_std(4, s, m, z));
    CHECK_OK(bingham_angular_spread(4, m, z, sp));
    CHECK(std::fabs(sp[3] * 180 / PI - 5.0) < 0.01);
}

// ---- (e) log-likelihood of a vector ------------------------------------------------------------

static void test_log_likelihood_vector() {
    const std::vector<Node> &nodes = nodes4();
    const size_t n = nodes.size();
    std::vector<double> p(n);
    const double kappas[] = {0.3, 2.0, 8.0};
    for (int rep = 0; rep < 4; ++rep) {
        MatrixXd m = random_orthogonal(rng, 4);
        VectorXd z = random_z(rng, 4, -12, 0), b = random_unit(rng, 3), r = random_unit(rng, 3);
        std::vector<double> mr = row_major(m);
        // f_state(q) = pdf(x0) exp(q^T A q - x0^T A x0), pdf(x0) from bingham_pdf at the mode x0
        // (bingham_pdf at all 10^6 nodes would recompute F per point; the state's total mass
        // below checks the normalization independently)
        VectorXd x0 = m.col(3);
        double p0 = 0;
        CHECK_OK(bingham_pdf(4, mr.data(), z.data(), 1, x0.data(), &p0));
        MatrixXd A = exponent(m, z);
        double a0 = quad_form(A, x0);
        for (size_t k = 0; k < n; ++k) p[k] = p0 * std::exp(nodes[k].x.dot(A * nodes[k].x) - a0);
        bingham_filter *f = NULL;
        CHECK_OK(bingham_filter_new(4, mr.data(), z.data(), &f));
        if (!f) return;
        std::vector<double> cosang(n);
        for (size_t k = 0; k < n; ++k) cosang[k] = r.dot(rotation(nodes[k].x) * b);
        for (double kappa : kappas) {
            // kappa / (4 pi sinh kappa) exp(kappa c) = kappa / (2 pi (1 - e^{-2 kappa})) exp(kappa (c - 1))
            double norm = kappa / (2 * PI * (1 - std::exp(-2 * kappa)));
            double integral = 0, mass = 0;
            for (size_t k = 0; k < n; ++k) {
                integral += nodes[k].w * p[k] * norm * std::exp(kappa * (cosang[k] - 1));
                mass += nodes[k].w * p[k];
            }
            CHECK_CLOSE(mass, 1.0, 1e-10);
            double ll = 0;
            CHECK_OK(bingham_filter_log_likelihood_vector(f, b.data(), r.data(), kappa, &ll));
            double rel = std::fabs(std::exp(ll) / integral - 1);
            CHECK(rel < 1e-6);
            if (!(rel < 1e-6)) fprintf(stderr, "    log_likelihood_vector kappa=%g: rel %.3g\n", kappa, rel);
        }
        // kappa = 0: the uniform density on S^2, 1 / (4 pi)
        double ll0 = 0;
        CHECK_OK(bingham_filter_log_likelihood_vector(f, b.data(), r.data(), 0.0, &ll0));
        CHECK_CLOSE(ll0, -std::log(4 * PI), 1e-12);
        bingham_filter_free(f);
    }
}

int main() {
    test_vector_observation();
    test_update_vector();
    test_noise_from_angle_std();
    test_angular_spread();
    test_log_likelihood_vector();
    return check_summary("vector_eigen");
}
