// What a C++ user sees, checked against references computed here from scratch, independently
// of the library:
//
// - F, dF/dz_i, the Hessian of log F, second moments, pdf, entropy, KL divergence: brute-force
//   quadrature over the sphere (d = 2: trapezoid rule in the angle; d = 3: Gauss-Legendre in the
//   polar angle x trapezoid in the azimuth; d = 4: hyperspherical coordinates, Gauss-Legendre in
//   two angles x trapezoid in the third), moderate concentrations |z| <= 20, full matrices
//   A = M Z M^T (so the library's handling of M is tested, not just Z).
// - d = 5, 6 (the library's general method): Kume & Wood's identity
//   dF_d/dz_1 (z) = F_{d+2}(z_1, z_1, z_1, z_2, ...) / (2 pi), the left side by quadrature at d = 3, 4.
// - multiply, mode, MLE directions: Eigen::SelfAdjointEigenSolver (columns compared up to sign).
// - compose: the exact moment algebra E[(x (+) y)(x (+) y)^T] = sum A_ab B_ce vec(e_a (+) e_c)
//   vec(e_b (+) e_e)^T, with A, B the input second moments from the quadrature above and the
//   products of basis elements taken with std::complex (d = 2) and Eigen::Quaterniond (d = 4,
//   constructed scalar first as Quaterniond(w, x, y, z)); compared with the second moment of the
//   library's moment-matched result.
// - rotate_left/right: pdf_rotated(u (+) x) = pdf(x), resp. pdf_rotated(x (+) u) = pdf(x), with
//   the products again from std::complex / Eigen::Quaterniond.
// - sample: empirical second moments of many samples against the quadrature.
#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include "check.h"
#include "eigen_util.hpp"
#include "sphere_quadrature.hpp"

using Eigen::MatrixXd;
using Eigen::VectorXd;
using namespace eigen_util;

static const std::vector<Node> &nodes_for(int d) {
    static std::vector<Node> n2 = sphere_nodes(2, 64), n3 = sphere_nodes(3, 96), n4 = sphere_nodes(4, 72);
    return d == 2 ? n2 : d == 3 ? n3 : n4;
}

// Reference moments of Bingham(A) with A = M Z M^T, by quadrature.
struct Reference {
    double F;        // normalization constant
    MatrixXd S;      // E[x x^T]
    MatrixXd X4;     // E[x_i^2 x_j^2]
    double EA;       // E[x^T A x]
};

static Reference reference(const MatrixXd &A) {
    int d = (int)A.rows();
    Reference r;
    r.F = 0;
    r.S = MatrixXd::Zero(d, d);
    r.X4 = MatrixXd::Zero(d, d);
    r.EA = 0;
    for (const Node &nd : nodes_for(d)) {
        double q = quad_form(A, nd.x), e = nd.w * std::exp(q);
        r.F += e;
        add_outer(r.S, e, nd.x);
        VectorXd sq = nd.x.cwiseProduct(nd.x);
        add_outer(r.X4, e, sq);
        r.EA += e * q;
    }
    r.S /= r.F;
    r.X4 /= r.F;
    r.EA /= r.F;
    return r;
}

// ---- helpers ------------------------------------------------------------------------------

static std::mt19937_64 rng(20240611);


static MatrixXd precision(const MatrixXd &m, const VectorXd &z) { return m * z.asDiagonal() * m.transpose(); }


// Columns equal up to sign.
static bool same_columns_up_to_sign(const MatrixXd &a, const MatrixXd &b, double tol) {
    for (int j = 0; j < a.cols(); ++j)
        if (std::fabs(std::fabs(a.col(j).dot(b.col(j))) - 1.0) > tol) return false;
    return true;
}

// Composition x (+) y, d = 2 (complex) or 4 (Hamilton product, scalar first).
// ---- tests --------------------------------------------------------------------------------

static const double Z_CASES[][4] = {
    {0, 0, 0, 0}, {-1, 0, -3, -2}, {-20, -5, 0, -12}, {2, -7, 5, -1}, {-0.5, -0.5, 0, -20}, {-15, -15, -15, 0},
};

static void test_normalization() {
    for (int d = 2; d <= 4; ++d)
        for (const double *zc : Z_CASES) {
            VectorXd z = Eigen::Map<const VectorXd>(zc, d);
            Reference r = reference(MatrixXd(z.asDiagonal()));
            double f, df[4], lf, dlf[4], hess[16], lf2;
            CHECK_OK(bingham_normalization_constant(d, z.data(), &f, df));
            CHECK_OK(bingham_log_normalization_constant(d, z.data(), &lf, dlf));
            CHECK_OK(bingham_log_normalization_hessian(d, z.data(), &lf2, NULL, hess));
            CHECK_CLOSE(f / r.F, 1.0, 1e-11);
            CHECK_CLOSE(lf, std::log(r.F), 1e-11);
            CHECK_CLOSE(lf2, lf, 1e-14);
            for (int i = 0; i < d; ++i) {
                CHECK_CLOSE(df[i] / r.F, r.S(i, i), 1e-11);
                CHECK_CLOSE(dlf[i], r.S(i, i), 1e-11);
                for (int j = 0; j < d; ++j)
                    CHECK_CLOSE(hess[i * d + j], r.X4(i, j) - r.S(i, i) * r.S(j, j), 1e-10);
            }
            double ls;
            CHECK_OK(bingham_log_normalization_constant_saddlepoint(d, z.data(), &ls, NULL));
            CHECK(std::fabs(ls - std::log(r.F)) < 0.06);
        }
}

// d = 5, 6 against d = 3, 4 quadrature: dF_d/dz_1 (z) = F_{d+2}(z_1, z_1, z_1, z_2, ...) / (2 pi).
static void test_higher_dimensions_by_identity() {
    for (int d = 3; d <= 4; ++d)
        for (const double *zc : Z_CASES) {
            VectorXd z = Eigen::Map<const VectorXd>(zc, d);
            Reference r = reference(MatrixXd(z.asDiagonal()));
            for (int i = 0; i < d; ++i) {
                std::vector<double> zz;
                for (int k = 0; k < d; ++k) {
                    zz.push_back(z(k));
                    if (k == i) {
                        zz.push_back(z(k));
                        zz.push_back(z(k));
                    }
                }
                double lf;
                CHECK_OK(bingham_log_normalization_constant(d + 2, zz.data(), &lf, NULL));
                CHECK_CLOSE(std::exp(lf) / (2 * PI) / (r.F * r.S(i, i)), 1.0, 1e-10);
            }
        }
}

static void test_moments_pdf_entropy_kl_mode() {
    for (int d = 2; d <= 4; ++d)
        for (int c = 1; c < 6; ++c) {
            VectorXd z = Eigen::Map<const VectorXd>(Z_CASES[c], d);
            MatrixXd m = random_orthogonal(rng, d);
            MatrixXd a = precision(m, z);
            Reference r = reference(a);
            std::vector<double> mr = row_major(m), s(d * d);
            CHECK_OK(bingham_second_moment(d, mr.data(), z.data(), s.data()));
            CHECK(max_abs(from_row_major(s, d) - r.S) < 1e-11);
            // pdf and log pdf at random points
            const int n = 5;
            std::vector<double> x, p(n), lp(n);
            for (int k = 0; k < n; ++k) {
                VectorXd v = random_unit(rng, d);
                x.insert(x.end(), v.data(), v.data() + d);
            }
            CHECK_OK(bingham_pdf(d, mr.data(), z.data(), n, x.data(), p.data()));
            CHECK_OK(bingham_log_pdf(d, mr.data(), z.data(), n, x.data(), lp.data()));
            for (int k = 0; k < n; ++k) {
                VectorXd v = Eigen::Map<const VectorXd>(&x[k * d], d);
                double q = quad_form(a, v);
                CHECK_CLOSE(p[k] / (std::exp(q) / r.F), 1.0, 1e-11);
                CHECK_CLOSE(lp[k], q - std::log(r.F), 1e-11);
            }
            // entropy = log F - E[x^T A x]
            double h;
            CHECK_OK(bingham_entropy(d, mr.data(), z.data(), &h));
            CHECK_CLOSE(h, std::log(r.F) - r.EA, 1e-10);
            // KL(p1 || p2) = E_p1[log p1 - log p2]
            VectorXd z2 = Eigen::Map<const VectorXd>(Z_CASES[(c % 5) + 1], d) * 0.5;
            MatrixXd m2 = random_orthogonal(rng, d), a2 = precision(m2, z2);
            Reference r2 = reference(a2);
            double kl_ref = 0;
            for (const Node &nd : nodes_for(d)) {
                double q1 = quad_form(a, nd.x), q2 = quad_form(a2, nd.x);
                kl_ref += nd.w * std::exp(q1) / r.F * ((q1 - std::log(r.F)) - (q2 - std::log(r2.F)));
            }
            std::vector<double> m2r = row_major(m2);
            double kl;
            CHECK_OK(bingham_kl_divergence(d, mr.data(), z.data(), m2r.data(), z2.data(), &kl));
            CHECK_CLOSE(kl, kl_ref, 1e-10);
            CHECK(kl >= 0);
            CHECK_OK(bingham_kl_divergence(d, mr.data(), z.data(), mr.data(), z.data(), &kl));
            CHECK(std::fabs(kl) < 1e-12);
            // mode: eigenvector of the largest eigenvalue of A (unique in these cases)
            Eigen::SelfAdjointEigenSolver<MatrixXd> es(a);
            if (es.eigenvalues()(d - 1) - es.eigenvalues()(d - 2) > 1e-6) {
                std::vector<double> mode(d);
                CHECK_OK(bingham_mode(d, mr.data(), z.data(), mode.data()));
                CHECK(std::fabs(std::fabs(es.eigenvectors().col(d - 1).dot(Eigen::Map<VectorXd>(mode.data(), d))) - 1) < 1e-12);
            }
        }
}

static void test_multiply() {
    for (int d : {2, 3, 4, 6})
        for (int c = 0; c < 5; ++c) {
            std::normal_distribution<double> g;
            VectorXd z1(d), z2(d);
            for (int i = 0; i < d; ++i) {
                z1(i) = 10 * g(rng);
                z2(i) = 10 * g(rng);
            }
            MatrixXd m1 = random_orthogonal(rng, d), m2 = random_orthogonal(rng, d);
            std::vector<double> m1r = row_major(m1), m2r = row_major(m2), m(d * d), z(d);
            CHECK_OK(bingham_multiply(d, m1r.data(), z1.data(), m2r.data(), z2.data(), m.data(), z.data()));
            Eigen::SelfAdjointEigenSolver<MatrixXd> es(precision(m1, z1) + precision(m2, z2));
            VectorXd lam = es.eigenvalues().array() - es.eigenvalues()(d - 1);
            MatrixXd mm = from_row_major(m, d);
            VectorXd zz = Eigen::Map<VectorXd>(z.data(), d);
            CHECK(z[d - 1] == 0.0);
            CHECK((zz - lam).cwiseAbs().maxCoeff() < 1e-11 * (1 + lam.cwiseAbs().maxCoeff()));
            CHECK(same_columns_up_to_sign(mm, es.eigenvectors(), 1e-10));
            CHECK(max_abs(mm.transpose() * mm - MatrixXd::Identity(d, d)) < 1e-13);
        }
}

static void test_mle() {
    for (int d = 2; d <= 4; ++d)
        for (int c = 1; c < 6; ++c) {
            if (c == 5 && d < 4) continue; // repeated z: directions not unique
            VectorXd z = Eigen::Map<const VectorXd>(Z_CASES[c], d);
            MatrixXd m = random_orthogonal(rng, d);
            Reference r = reference(precision(m, z));
            std::vector<double> s = row_major(r.S), mo(d * d), zo(d);
            CHECK_OK(bingham_mle(d, s.data(), mo.data(), zo.data()));
            // z: the truth, sorted and shifted
            std::vector<double> zt(z.data(), z.data() + d);
            std::sort(zt.begin(), zt.end());
            for (int i = 0; i < d; ++i) CHECK_CLOSE(zo[i], zt[i] - zt[d - 1], 1e-8);
            // M: eigenvectors of S (ascending eigenvalues), up to sign
            Eigen::SelfAdjointEigenSolver<MatrixXd> es(r.S);
            bool distinct = true;
            for (int i = 0; i + 1 < d; ++i) distinct = distinct && zt[i + 1] - zt[i] > 1e-9;
            if (distinct) CHECK(same_columns_up_to_sign(from_row_major(mo, d), es.eigenvectors(), 1e-9));
            // the fit reproduces S (moment matching)
            std::vector<double> s2(d * d);
            CHECK_OK(bingham_second_moment(d, mo.data(), zo.data(), s2.data()));
            CHECK(max_abs(from_row_major(s2, d) - r.S) < 1e-11);
        }
    // from weighted samples: the same as the MLE of the weighted scatter matrix
    for (int d : {2, 3, 4, 5}) {
        const int n = 50;
        std::vector<double> x, w, wone(n, 1.0);
        MatrixXd t = MatrixXd::Zero(d, d), t1 = MatrixXd::Zero(d, d);
        double wsum = 0;
        VectorXd axis = random_unit(rng, d);
        for (int k = 0; k < n; ++k) {
            VectorXd v = (axis * 3.0 * (k % 2 ? 1 : -1) + random_unit(rng, d)).normalized();
            x.insert(x.end(), v.data(), v.data() + d);
            double wk = 0.1 + (k % 7);
            w.push_back(wk);
            add_outer(t, wk, v);
            t1 += v * v.transpose();
            wsum += wk;
        }
        t /= wsum;
        t1 /= n;
        std::vector<double> m(d * d), z(d), mref(d * d), zref(d), tr = row_major(t), t1r = row_major(t1);
        CHECK_OK(bingham_mle_samples(d, n, x.data(), w.data(), m.data(), z.data()));
        CHECK_OK(bingham_mle(d, tr.data(), mref.data(), zref.data()));
        for (int i = 0; i < d; ++i) CHECK_CLOSE(z[i], zref[i], 1e-8);
        Eigen::SelfAdjointEigenSolver<MatrixXd> es(t);
        CHECK(same_columns_up_to_sign(from_row_major(m, d), es.eigenvectors(), 1e-9));
        // no weights = equal weights
        CHECK_OK(bingham_mle_samples(d, n, x.data(), NULL, m.data(), z.data()));
        CHECK_OK(bingham_mle_samples(d, n, x.data(), wone.data(), mref.data(), zref.data()));
        for (int i = 0; i < d; ++i) CHECK_CLOSE(z[i], zref[i], 1e-12);
        CHECK_OK(bingham_mle(d, t1r.data(), mref.data(), zref.data()));
        for (int i = 0; i < d; ++i) CHECK_CLOSE(z[i], zref[i], 1e-8);
    }
}

// Exact second moment of x (+) y for independent x, y with second moments A, B.
static MatrixXd composed_moment(const MatrixXd &a, const MatrixXd &b) {
    int d = (int)a.rows();
    MatrixXd s = MatrixXd::Zero(d, d);
    for (int i = 0; i < d; ++i)
        for (int j = 0; j < d; ++j)
            for (int k = 0; k < d; ++k)
                for (int l = 0; l < d; ++l) {
                    VectorXd ei = VectorXd::Unit(d, i), ej = VectorXd::Unit(d, j), ek = VectorXd::Unit(d, k),
                             el = VectorXd::Unit(d, l);
                    s += a(i, j) * b(k, l) * compose_vectors(ei, ek) * compose_vectors(ej, el).transpose();
                }
    return s;
}

static void test_compose() {
    for (int d : {2, 4})
        for (int c = 1; c < 6; ++c) {
            VectorXd z1 = Eigen::Map<const VectorXd>(Z_CASES[c], d);
            VectorXd z2 = Eigen::Map<const VectorXd>(Z_CASES[(c + 2) % 5 + 1], d);
            MatrixXd m1 = random_orthogonal(rng, d), m2 = random_orthogonal(rng, d);
            Reference r1 = reference(precision(m1, z1)), r2 = reference(precision(m2, z2));
            MatrixXd expected = composed_moment(r1.S, r2.S);
            std::vector<double> m1r = row_major(m1), m2r = row_major(m2), m(d * d), z(d), s(d * d);
            CHECK_OK(bingham_compose(d, m1r.data(), z1.data(), m2r.data(), z2.data(), m.data(), z.data()));
            CHECK_OK(bingham_second_moment(d, m.data(), z.data(), s.data()));
            CHECK(max_abs(from_row_major(s, d) - expected) < 1e-9);
            CHECK(std::fabs(expected.trace() - 1) < 1e-12);
        }
    // the filter paper's d = 2 setting: noise with mode (1, 0) (the identity) keeps the mode
    // (0, 1) of the state and spreads it a little
    double ms[4] = {1, 0, 0, 1}, mw[4] = {0, 1, 1, 0}, za[2] = {-1, 0}, zb[2] = {-200, 0}, m[4], z[2];
    CHECK_OK(bingham_compose(2, ms, za, mw, zb, m, z));
    CHECK(std::fabs(std::fabs(m[3]) - 1) < 1e-12 && z[0] < -0.5 && z[0] > -1);
}

static void test_rotate() {
    for (int d : {2, 4})
        for (int c = 1; c < 4; ++c) {
            VectorXd z = Eigen::Map<const VectorXd>(Z_CASES[c], d);
            MatrixXd m = random_orthogonal(rng, d);
            VectorXd u = random_unit(rng, d);
            std::vector<double> mr = row_major(m), ml(d * d), zl(d), mrr(d * d), zrr(d);
            CHECK_OK(bingham_rotate_left(d, mr.data(), z.data(), u.data(), ml.data(), zl.data()));
            CHECK_OK(bingham_rotate_right(d, mr.data(), z.data(), u.data(), mrr.data(), zrr.data()));
            for (int k = 0; k < 5; ++k) {
                VectorXd x = random_unit(rng, d), ux = compose_vectors(u, x), xu = compose_vectors(x, u);
                double p, pl, pr;
                CHECK_OK(bingham_log_pdf(d, mr.data(), z.data(), 1, x.data(), &p));
                CHECK_OK(bingham_log_pdf(d, ml.data(), zl.data(), 1, ux.data(), &pl));
                CHECK_OK(bingham_log_pdf(d, mrr.data(), zrr.data(), 1, xu.data(), &pr));
                CHECK_CLOSE(pl, p, 1e-12);
                CHECK_CLOSE(pr, p, 1e-12);
            }
        }
}

static void test_sample() {
    for (int d = 2; d <= 4; ++d) {
        VectorXd z = Eigen::Map<const VectorXd>(Z_CASES[2], d);
        MatrixXd m = random_orthogonal(rng, d);
        Reference r = reference(precision(m, z));
        std::vector<double> mr = row_major(m);
        const int n = 40000;
        std::vector<double> x((size_t)n * d);
        CHECK_OK(bingham_sample(d, mr.data(), z.data(), 7, n, x.data()));
        MatrixXd s = MatrixXd::Zero(d, d);
        double worst_norm = 0;
        for (int k = 0; k < n; ++k) {
            VectorXd v = Eigen::Map<const VectorXd>(&x[(size_t)k * d], d);
            s += v * v.transpose();
            worst_norm = std::max(worst_norm, std::fabs(v.norm() - 1));
        }
        s /= n;
        CHECK(worst_norm < 1e-12);
        // standard error of a mean of x_i x_j <= 0.5/sqrt(n) = 0.0025; allow 5 of them
        CHECK(max_abs(s - r.S) < 0.0125);
    }
}

int main() {
    test_normalization();
    test_higher_dimensions_by_identity();
    test_moments_pdf_entropy_kl_mode();
    test_multiply();
    test_mle();
    test_compose();
    test_rotate();
    test_sample();
    return check_summary("reference_eigen");
}
