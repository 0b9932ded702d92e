// The recursive Bingham filter (bingham_filter_*) against references computed here from scratch
// with Eigen, independently of the library's own mathematics:
//
// - predict: the moment of the composition E[(x (+) w)(x (+) w)^T] = sum A_ab B_ce
//   vec(e_a (+) e_c) vec(e_b (+) e_e)^T, with the products of basis elements taken with
//   std::complex (d = 2) and Eigen::Quaterniond (d = 4, constructed scalar first as
//   Quaterniond(w, x, y, z)), A and B the second moments of state and noise by brute-force
//   quadrature on the sphere; the filter's prediction must have exactly this second moment
//   (moment matching), again by quadrature. Also a sampled check: the empirical moment of
//   x (+) w for samples of state and noise (bingham_sample), within 5 standard errors.
// - predict_rotation: E[(x (+) u)(x (+) u)^T] by quadrature of the rotated points, then as above.
// - update: the posterior exponent M Z M^T + M_L Z_v M_L^T with M_L's columns z (+) conj(m_i)
//   (Quaterniond / std::complex), eigendecomposed by Eigen::SelfAdjointEigenSolver; compared
//   with the filter's posterior (z exactly shifted, columns up to sign).
// - log_likelihood: log of the quadrature of f_state(x) f_v(conj(x) (+) z) over the sphere.
// - invariants: a measurement at the mode with aligned noise adds the concentrations and keeps
//   the mode; identity-mode isotropic noise keeps M and lowers |z|.
//
// Concentrations |z| <= 25, where the quadrature (sphere_quadrature.hpp: trapezoid rule for
// d = 2; Gauss-Legendre x Gauss-Legendre x trapezoid in hyperspherical coordinates for d = 4) is
// accurate to ~1e-12.
#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <complex>
#include <random>
#include <vector>

#include "check.h"
#include "eigen_util.hpp"
#include "sphere_quadrature.hpp"

using Eigen::MatrixXd;
using Eigen::VectorXd;
using namespace eigen_util;

static const std::vector<Node> &nodes(int d) {
    // 512 points on S^1; 80 x 80 x 160 on S^3
    static std::vector<Node> n2 = sphere_nodes(2, 128), n4 = sphere_nodes(4, 80);
    return d == 2 ? n2 : n4;
}

static MatrixXd exponent_matrix(const MatrixXd &m, const VectorXd &z) { return m * z.asDiagonal() * m.transpose(); }

// log F and E[x x^T] of the density prop. to exp(x^T A x), by quadrature.
static void moments(const MatrixXd &A, double &log_f, MatrixXd &S) {
    int d = (int)A.rows();
    // shift by the largest eigenvalue so the exponent is <= 0
    double top = Eigen::SelfAdjointEigenSolver<MatrixXd>(A).eigenvalues().maxCoeff();
    double F = 0;
    S = MatrixXd::Zero(d, d);
    for (const Node &nd : nodes(d)) {
        double e = nd.w * std::exp(quad_form(A, nd.x) - top);
        F += e;
        add_outer(S, e, nd.x);
    }
    S /= F;
    log_f = std::log(F) + top;
}

// E[(x (+) u)(x (+) u)^T] for x prop. to exp(x^T A x), by quadrature of the rotated points.
static MatrixXd rotated_moment(const MatrixXd &A, const VectorXd &u) {
    int d = (int)A.rows();
    double top = Eigen::SelfAdjointEigenSolver<MatrixXd>(A).eigenvalues().maxCoeff(), F = 0;
    MatrixXd S = MatrixXd::Zero(d, d);
    for (const Node &nd : nodes(d)) {
        double e = nd.w * std::exp(quad_form(A, nd.x) - top);
        VectorXd y = compose_vectors(nd.x, u);
        F += e;
        add_outer(S, e, y);
    }
    return S / F;
}

// ---- algebra with std::complex / Eigen::Quaterniond --------------------------------------------

static VectorXd conjugate(const VectorXd &x) {
    VectorXd r = -x;
    r(0) = x(0);
    return r;
}

static VectorXd basis(int d, int a) {
    VectorXd e = VectorXd::Zero(d);
    e(a) = 1;
    return e;
}

// E[(x (+) y)(x (+) y)^T] = sum_{a,b,c,e} A_ab B_ce (e_a (+) e_c)(e_b (+) e_e)^T
static MatrixXd compose_moments(const MatrixXd &A, const MatrixXd &B) {
    int d = (int)A.rows();
    MatrixXd C = MatrixXd::Zero(d, d);
    for (int a = 0; a < d; ++a)
        for (int b = 0; b < d; ++b)
            for (int c = 0; c < d; ++c)
                for (int e = 0; e < d; ++e)
                    C += A(a, b) * B(c, e) * compose_vectors(basis(d, a), basis(d, c)) *
                         compose_vectors(basis(d, b), basis(d, e)).transpose();
    return C;
}

// ---- helpers ---------------------------------------------------------------------------------

static std::mt19937_64 rng(4242);


struct State {
    MatrixXd m;
    VectorXd z;
};

static State get_state(const bingham_filter *f, int d) {
    std::vector<double> m(d * d), z(d);
    CHECK_OK(bingham_filter_get_state(f, m.data(), z.data()));
    State s{MatrixXd(d, d), VectorXd(d)};
    for (int i = 0; i < d; ++i) {
        s.z(i) = z[i];
        for (int j = 0; j < d; ++j) s.m(i, j) = m[i * d + j];
    }
    return s;
}

static bingham_filter *make_filter(const MatrixXd &m, const VectorXd &z) {
    bingham_filter *f = NULL;
    std::vector<double> mr = row_major(m);
    CHECK_OK(bingham_filter_new((size_t)m.rows(), mr.data(), z.data(), &f));
    return f;
}

// ---- tests -----------------------------------------------------------------------------------

static void test_predict(int d) {
    for (int rep = 0; rep < 4; ++rep) {
        MatrixXd m = random_orthogonal(rng, d), mw = random_orthogonal(rng, d);
        VectorXd z = random_z(rng, d, -25, 0), zw = random_z(rng, d, -25, 0);
        bingham_filter *f = make_filter(m, z);
        double lf;
        MatrixXd A, B, S;
        moments(exponent_matrix(m, z), lf, A);
        moments(exponent_matrix(mw, zw), lf, B);
        MatrixXd C = compose_moments(A, B);
        std::vector<double> mwr = row_major(mw);
        CHECK_OK(bingham_filter_predict(f, mwr.data(), zw.data()));
        State p = get_state(f, d);
        moments(exponent_matrix(p.m, p.z), lf, S);
        CHECK(max_abs(S - C) < 1e-10);
        if (!(max_abs(S - C) < 1e-10)) fprintf(stderr, "    predict d=%d: %.3g\n", d, max_abs(S - C));

        // with a known rotation u: x (+) u (+) w
        VectorXd u = random_unit(rng, d);
        bingham_filter_free(f);
        f = make_filter(m, z);
        CHECK_OK(bingham_filter_predict_rotation(f, u.data(), mwr.data(), zw.data()));
        C = compose_moments(rotated_moment(exponent_matrix(m, z), u), B);
        p = get_state(f, d);
        moments(exponent_matrix(p.m, p.z), lf, S);
        CHECK(max_abs(S - C) < 1e-10);
        if (!(max_abs(S - C) < 1e-10)) fprintf(stderr, "    predict_rotation d=%d: %.3g\n", d, max_abs(S - C));
        bingham_filter_free(f);
    }
}

// Sampled check of the composition: the empirical second moment of x (+) w for n samples of the
// state and the noise, entry by entry within 5 standard errors of the predicted state's moment.
static void test_predict_sampled(int d) {
    const size_t n = 200000;
    MatrixXd m = random_orthogonal(rng, d), mw = random_orthogonal(rng, d);
    VectorXd z = random_z(rng, d, -10, 0), zw = random_z(rng, d, -30, -5);
    std::vector<double> mr = row_major(m), mwr = row_major(mw), xs(n * d), ws(n * d);
    CHECK_OK(bingham_sample(d, mr.data(), z.data(), 11, n, xs.data()));
    CHECK_OK(bingham_sample(d, mwr.data(), zw.data(), 12, n, ws.data()));
    MatrixXd sum = MatrixXd::Zero(d, d), sum2 = MatrixXd::Zero(d, d);
    for (size_t k = 0; k < n; ++k) {
        VectorXd x = Eigen::Map<VectorXd>(&xs[k * d], d), w = Eigen::Map<VectorXd>(&ws[k * d], d);
        VectorXd y = compose_vectors(x, w);
        MatrixXd yy = y * y.transpose();
        sum += yy;
        sum2 += yy.cwiseProduct(yy);
    }
    MatrixXd mean = sum / n, var = sum2 / n - mean.cwiseProduct(mean);
    bingham_filter *f = make_filter(m, z);
    CHECK_OK(bingham_filter_predict(f, mwr.data(), zw.data()));
    State p = get_state(f, d);
    std::vector<double> pm = row_major(p.m), s(d * d);
    CHECK_OK(bingham_second_moment(d, pm.data(), p.z.data(), s.data()));
    int bad = 0;
    for (int i = 0; i < d; ++i)
        for (int j = 0; j < d; ++j)
            if (std::fabs(s[i * d + j] - mean(i, j)) > 5 * std::sqrt(var(i, j) / n) + 1e-12) ++bad;
    CHECK(bad == 0);
    bingham_filter_free(f);
}

static void test_update(int d) {
    for (int rep = 0; rep < 6; ++rep) {
        MatrixXd m = random_orthogonal(rng, d), mv = random_orthogonal(rng, d);
        VectorXd z = random_z(rng, d, -25, 0), zv = random_z(rng, d, -25, 0), y = random_unit(rng, d);
        bingham_filter *f = make_filter(m, z);
        std::vector<double> mvr = row_major(mv);
        CHECK_OK(bingham_filter_update(f, y.data(), mvr.data(), zv.data()));
        State q = get_state(f, d);
        MatrixXd ml(d, d);
        for (int i = 0; i < d; ++i) ml.col(i) = compose_vectors(y, conjugate(mv.col(i)));
        Eigen::SelfAdjointEigenSolver<MatrixXd> es(exponent_matrix(m, z) + exponent_matrix(ml, zv));
        VectorXd lam = es.eigenvalues();  // ascending
        VectorXd zref = lam.array() - lam(d - 1);
        double scale = std::max(1.0, zref.cwiseAbs().maxCoeff());
        CHECK(max_abs(q.z - zref) < 1e-12 * scale);
        // the posterior as a whole (independent of column signs and of near-ties) ...
        CHECK(max_abs(exponent_matrix(q.m, q.z) - exponent_matrix(es.eigenvectors(), zref)) < 1e-12 * scale);
        // ... and the principal directions where the eigenvalues are well separated
        for (int j = 0; j < d; ++j) {
            double gap = 1e300;
            for (int i = 0; i < d; ++i)
                if (i != j) gap = std::min(gap, std::fabs(lam(i) - lam(j)));
            if (gap > 0.5) CHECK(std::fabs(std::fabs(q.m.col(j).dot(es.eigenvectors().col(j))) - 1) < 1e-12);
        }
        CHECK(max_abs(q.m.transpose() * q.m - MatrixXd::Identity(d, d)) < 1e-14);
        bingham_filter_free(f);
    }
}

static void test_log_likelihood(int d) {
    for (int rep = 0; rep < 4; ++rep) {
        MatrixXd m = random_orthogonal(rng, d), mv = random_orthogonal(rng, d);
        VectorXd z = random_z(rng, d, -15, 0), zv = random_z(rng, d, -15, 0), y = random_unit(rng, d);
        bingham_filter *f = make_filter(m, z);
        std::vector<double> mvr = row_major(mv);
        double ll = 0, lf_s, lf_v;
        MatrixXd S;
        MatrixXd As = exponent_matrix(m, z), Av = exponent_matrix(mv, zv);
        moments(As, lf_s, S);
        moments(Av, lf_v, S);
        double integral = 0;
        for (const Node &nd : nodes(d)) {
            VectorXd v = compose_vectors(conjugate(nd.x), y);  // x^-1 (+) z
            integral += nd.w * std::exp(quad_form(As, nd.x) - lf_s + quad_form(Av, v) - lf_v);
        }
        CHECK_OK(bingham_filter_log_likelihood(f, y.data(), mvr.data(), zv.data(), &ll));
        CHECK_CLOSE(ll, std::log(integral), 1e-10);
        bingham_filter_free(f);
    }
}

static void test_invariants(int d) {
    for (int rep = 0; rep < 4; ++rep) {
        MatrixXd m = random_orthogonal(rng, d);
        VectorXd z = random_z(rng, d, -25, 0);
        std::sort(z.data(), z.data() + d);
        bingham_filter *f = make_filter(m, z);
        State s0 = get_state(f, d);
        VectorXd mode = s0.m.col(d - 1);
        // aligned noise: M_v = D L(mode)^T M, i.e. columns conj(conj(mode) (+) m_i)
        MatrixXd mv(d, d);
        for (int i = 0; i < d; ++i) mv.col(i) = conjugate(compose_vectors(conjugate(mode), s0.m.col(i)));
        VectorXd zv = random_z(rng, d, -25, 0);
        std::vector<double> mvr = row_major(mv);
        CHECK_OK(bingham_filter_update(f, mode.data(), mvr.data(), zv.data()));
        State s1 = get_state(f, d);
        VectorXd sum = s0.z + zv;
        std::sort(sum.data(), sum.data() + d);
        CHECK(max_abs(s1.z - sum) < 1e-12 * std::max(1.0, sum.cwiseAbs().maxCoeff()));
        CHECK(std::fabs(std::fabs(s1.m.col(d - 1).dot(mode)) - 1) < 1e-13);
        bingham_filter_free(f);

        // identity-mode noise, isotropic around it: M kept, |z| lowered
        f = make_filter(m, z);
        MatrixXd mw = MatrixXd::Zero(d, d);
        for (int i = 0; i + 1 < d; ++i) mw(i + 1, i) = 1;
        mw(0, d - 1) = 1;
        VectorXd zw = VectorXd::Constant(d, -40);
        zw(d - 1) = 0;
        std::vector<double> mwr = row_major(mw);
        CHECK_OK(bingham_filter_predict(f, mwr.data(), zw.data()));
        State s2 = get_state(f, d);
        for (int i = 0; i + 1 < d; ++i) CHECK(s2.z(i) > s0.z(i) && s2.z(i) < 0);
        for (int j = 0; j < d; ++j) {
            double gap = 1e300;
            for (int i = 0; i < d; ++i)
                if (i != j) gap = std::min(gap, std::fabs(s0.z(i) - s0.z(j)));
            if (gap > 0.5) CHECK(std::fabs(std::fabs(s2.m.col(j).dot(s0.m.col(j))) - 1) < 1e-10);
        }
        bingham_filter_free(f);
    }
}

int main() {
    for (int d = 2; d <= 4; d += 2) {
        test_predict(d);
        test_predict_sampled(d);
        test_update(d);
        test_log_likelihood(d);
        test_invariants(d);
    }
    return check_summary("filter_eigen");
}
