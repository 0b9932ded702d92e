// The world-frame filter steps (bingham_filter_predict_world, _update_world,
// _log_likelihood_world) and the spin filter (bingham_spin_filter_*) against references written
// here with Eigen (quaternions scalar first, Eigen::Quaterniond(w, x, y, z); q o r = q * r, the
// Hamilton product; std::complex for d = 2):
//
// - predict_world: the second moment of w o u o x, E = sum_ab B_ab L(e_a) (L(u) A L(u)^T) L(e_b)^T
//   with L(q) r = q o r built column by column from Eigen products, A and B the second moments
//   of state and noise (bingham_second_moment); the new state's second moment must equal it to
//   1e-10 (the fit matches the moment). The reference tells the frames apart: for the
//   anisotropic noises the body-frame moment (x o w) differs from it by far more than the
//   tolerance. A Monte Carlo check: samples of x and w (bingham_sample), w o u o x formed with
//   Eigen, the sample second moment within 5 standard errors entrywise (z_w = (0, -10, -10, -1)
//   and (0, -400, -400, -10) at the identity, d = 4). For d = 2 predict_world equals
//   predict_rotation (complex multiplication commutes).
// - update_world: the likelihood Bingham(x; Z_v, V^-1 o y), its columns conj(v_i) o y computed
//   with Eigen (and checked to be f_v(y o x^-1) up to a constant at random x), multiplied into the
//   prior with bingham_multiply and, independently, with Eigen's SelfAdjointEigenSolver; the
//   posterior M Z M^T must agree to 1e-10 (relative).
// - log_likelihood_world: log of the brute-force quadrature on the sphere (sphere_quadrature.hpp,
//   |z| <= 15, accurate to ~1e-12) of f_state(x) f_v(y o x^-1).
// - spin filter: one step against the same step composed from the C distribution functions
//   (bingham_compose, bingham_multiply, bingham_rotate_left; the inverse of Bingham(M, Z) is
//   Bingham(D M, Z), D = diag(1, -1, -1, -1)), relative 1e-9 on M Z M^T; the compositions'
//   moments against the Eigen formula above (1e-10); the predictive log-likelihood against
//   quadrature of the composed prior times f_o(y o x^-1); a noiseless constant spin observed
//   every step (uniform orientation prior, spin prior (-3)^3 at the identity, observations
//   with random sign): the spin's and the orientation's modes converge to the truth (1e-6 rad).
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

static std::mt19937_64 rng(2213);

static const std::vector<Node> &nodes(int d) {
    // 512 points on S^1; 80 x 80 x 160 on S^3
    static std::vector<Node> n2 = sphere_nodes(2, 128), n4 = sphere_nodes(4, 80);
    return d == 2 ? n2 : n4;
}

// ---- algebra with Eigen::Quaterniond / std::complex --------------------------------------------

static VectorXd basis(int d, int a) {
    VectorXd e = VectorXd::Zero(d);
    e(a) = 1;
    return e;
}

static VectorXd conjugate(const VectorXd &x) {
    VectorXd r = -x;
    r(0) = x(0);
    return r;
}

// L(q): L(q) r = q o r; column j is q o e_j.
static MatrixXd left_matrix(const VectorXd &q) {
    int d = (int)q.size();
    MatrixXd l(d, d);
    for (int j = 0; j < d; ++j) l.col(j) = compose_vectors(q, basis(d, j));
    return l;
}

// R(q): R(q) r = r o q; column j is e_j o q.
static MatrixXd right_matrix(const VectorXd &q) {
    int d = (int)q.size();
    MatrixXd r(d, d);
    for (int j = 0; j < d; ++j) r.col(j) = compose_vectors(basis(d, j), q);
    return r;
}

// E[(w o y)(w o y)^T] for independent w (second moment B) and y (second moment Y):
// w o y = sum_a w_a L(e_a) y.
static MatrixXd world_moment(const MatrixXd &B, const MatrixXd &Y) {
    int d = (int)B.rows();
    MatrixXd C = MatrixXd::Zero(d, d);
    for (int a = 0; a < d; ++a)
        for (int b = 0; b < d; ++b)
            C += B(a, b) * left_matrix(basis(d, a)) * Y * left_matrix(basis(d, b)).transpose();
    return C;
}

// E[(y o w)(y o w)^T] (the body frame): y o w = sum_a w_a R(e_a) y.
static MatrixXd body_moment(const MatrixXd &Y, const MatrixXd &B) {
    int d = (int)B.rows();
    MatrixXd C = MatrixXd::Zero(d, d);
    for (int a = 0; a < d; ++a)
        for (int b = 0; b < d; ++b)
            C += B(a, b) * right_matrix(basis(d, a)) * Y * right_matrix(basis(d, b)).transpose();
    return C;
}

static MatrixXd exponent_matrix(const MatrixXd &m, const VectorXd &z) { return m * z.asDiagonal() * m.transpose(); }

static MatrixXd conjugation(int d) {
    MatrixXd D = -MatrixXd::Identity(d, d);
    D(0, 0) = 1;
    return D;
}

// The rotation angle between two unit quaternions (sign-blind), accurate for small angles.
static double angle(const VectorXd &a, const VectorXd &b) {
    VectorXd r = compose_vectors(conjugate(a), b);
    double s = r.tail(3).norm();
    return 2 * std::atan2(s, std::fabs(r(0)));
}

// ---- the library's distribution functions ----------------------------------------------------

struct Dist {
    MatrixXd m;
    VectorXd z;
};

static MatrixXd second_moment(const Dist &b) {
    int d = (int)b.z.size();
    std::vector<double> mr = row_major(b.m), s(d * d);
    CHECK_OK(bingham_second_moment(d, mr.data(), b.z.data(), s.data()));
    return from_row_major(s, d);
}

static Dist lib_binary(bingham_status (*fn)(size_t, const double *, const double *, const double *,
                                            const double *, double *, double *),
                       const Dist &a, const Dist &b) {
    int d = (int)a.z.size();
    std::vector<double> ma = row_major(a.m), mb = row_major(b.m), m(d * d);
    Dist r{MatrixXd(d, d), VectorXd(d)};
    CHECK_OK(fn(d, ma.data(), a.z.data(), mb.data(), b.z.data(), m.data(), r.z.data()));
    r.m = from_row_major(m, d);
    return r;
}

static Dist multiply(const Dist &a, const Dist &b) { return lib_binary(bingham_multiply, a, b); }
static Dist compose(const Dist &a, const Dist &b) { return lib_binary(bingham_compose, a, b); }

static Dist rotate_left(const Dist &a, const VectorXd &u) {
    int d = (int)a.z.size();
    std::vector<double> ma = row_major(a.m), m(d * d);
    Dist r{MatrixXd(d, d), VectorXd(d)};
    CHECK_OK(bingham_rotate_left(d, ma.data(), a.z.data(), u.data(), m.data(), r.z.data()));
    r.m = from_row_major(m, d);
    return r;
}

// The likelihood of y = v o x in x: Bingham(x; Z_v, columns conj(m_i) o y).
static Dist world_likelihood(const VectorXd &y, const Dist &noise) {
    int d = (int)y.size();
    Dist l{MatrixXd(d, d), noise.z};
    for (int i = 0; i < d; ++i) l.m.col(i) = compose_vectors(conjugate(noise.m.col(i)), y);
    return l;
}

// max |P_a - P_b| / max(1, max |z_a|) of the exponent matrices P = M Z M^T.
static double exponent_difference(const Dist &a, const Dist &b) {
    double scale = std::max(1.0, a.z.cwiseAbs().maxCoeff());
    return max_abs(exponent_matrix(a.m, a.z) - exponent_matrix(b.m, b.z)) / scale;
}

// log F of the density prop. to exp(x^T P x), by quadrature.
static double log_normalizer(const MatrixXd &P) {
    int d = (int)P.rows();
    double top = Eigen::SelfAdjointEigenSolver<MatrixXd>(P).eigenvalues().maxCoeff(), F = 0;
    for (const Node &nd : nodes(d)) F += nd.w * std::exp(quad_form(P, nd.x) - top);
    return std::log(F) + top;
}

// log of the quadrature of f_state(x) f_v(y o x^-1) over the sphere.
static double world_log_likelihood_quadrature(const Dist &state, const Dist &noise, const VectorXd &y) {
    int d = (int)y.size();
    MatrixXd As = exponent_matrix(state.m, state.z), Av = exponent_matrix(noise.m, noise.z);
    double lf_s = log_normalizer(As), lf_v = log_normalizer(Av), integral = 0;
    for (const Node &nd : nodes(d)) {
        VectorXd v = compose_vectors(y, conjugate(nd.x));  // y o x^-1
        integral += nd.w * std::exp(quad_form(As, nd.x) - lf_s + quad_form(Av, v) - lf_v);
    }
    return std::log(integral);
}

// ---- handles ---------------------------------------------------------------------------------

static Dist filter_state(const bingham_filter *f, int d) {
    std::vector<double> m(d * d);
    Dist s{MatrixXd(d, d), VectorXd(d)};
    CHECK_OK(bingham_filter_get_state(f, m.data(), s.z.data()));
    s.m = from_row_major(m, d);
    return s;
}

static bingham_filter *make_filter(const Dist &b) {
    bingham_filter *f = NULL;
    std::vector<double> mr = row_major(b.m);
    CHECK_OK(bingham_filter_new((size_t)b.z.size(), mr.data(), b.z.data(), &f));
    return f;
}

struct SpinState {
    Dist x, v;
};

static SpinState spin_state(const bingham_spin_filter *f) {
    double mx[16], zx[4], mv[16], zv[4];
    CHECK_OK(bingham_spin_filter_get_state(f, mx, zx, mv, zv));
    SpinState s{{from_row_major(mx, 4), Eigen::Map<VectorXd>(zx, 4)}, {from_row_major(mv, 4), Eigen::Map<VectorXd>(zv, 4)}};
    return s;
}

static bingham_spin_filter *make_spin(const Dist &x, const Dist &v) {
    bingham_spin_filter *f = NULL;
    std::vector<double> mx = row_major(x.m), mv = row_major(v.m);
    CHECK_OK(bingham_spin_filter_new(mx.data(), x.z.data(), mv.data(), v.z.data(), &f));
    return f;
}

static Dist random_dist(int d, double lo, double hi) {
    Dist b{random_orthogonal(rng, d), random_z(rng, d, lo, hi)};
    return b;
}

// Noise with its mode at the identity: M = I, z = (0, z1, z2, z3) (d = 4) or (0, z1) (d = 2).
static Dist identity_noise(const std::vector<double> &z) {
    int d = (int)z.size();
    Dist b{MatrixXd::Identity(d, d), Eigen::Map<const VectorXd>(z.data(), d)};
    return b;
}

// ---- predict_world ---------------------------------------------------------------------------

static void report(const char *what, int d, double err, double tol) {
    if (!(err < tol)) fprintf(stderr, "    %s d=%d: %.3g (tol %.3g)\n", what, d, err, tol);
}

static void test_predict_world_exact() {
    const int d = 4;
    std::vector<Dist> noises;
    noises.push_back(identity_noise({0, -10, -10, -1}));
    noises.push_back(identity_noise({0, -400, -400, -10}));
    noises.push_back(identity_noise({0, -50, -50, -50}));
    noises.push_back(random_dist(d, -200, -1));
    noises.push_back(random_dist(d, -30, 0));
    int discriminated = 0;
    for (size_t k = 0; k < noises.size(); ++k) {
        for (int rep = 0; rep < 3; ++rep) {
            Dist state = rep == 2 ? random_dist(d, -800, -100) : random_dist(d, -60, 0);
            bool with_u = rep != 1;
            VectorXd u = random_unit(rng, d);
            bingham_filter *f = make_filter(state);
            MatrixXd A = second_moment(state), B = second_moment(noises[k]);
            MatrixXd Y = with_u ? MatrixXd(left_matrix(u) * A * left_matrix(u).transpose()) : A;
            MatrixXd C = world_moment(B, Y);
            std::vector<double> mw = row_major(noises[k].m);
            CHECK_OK(bingham_filter_predict_world(f, with_u ? u.data() : NULL, mw.data(), noises[k].z.data()));
            MatrixXd S = second_moment(filter_state(f, d));
            double err = max_abs(S - C);
            CHECK(err < 1e-10);
            report("predict_world", d, err, 1e-10);
            // the reference is not the body frame's (x o u o w) for anisotropic noise
            double frames = max_abs(C - body_moment(Y, B));
            if (k < 2) {
                CHECK(frames > 1e-3);
                ++discriminated;
            }
            // a unit u within the tolerance is normalized: the same result
            VectorXd u2 = u * (1 + 5e-4);
            bingham_filter *g = make_filter(state);
            CHECK_OK(bingham_filter_predict_world(g, with_u ? u2.data() : NULL, mw.data(), noises[k].z.data()));
            CHECK(exponent_difference(filter_state(g, d), filter_state(f, d)) < 1e-10);
            bingham_filter_free(g);
            bingham_filter_free(f);
        }
    }
    CHECK(discriminated == 6);
}

static void test_predict_world_sampled() {
    const int d = 4;
    const size_t n = 200000;
    std::vector<Dist> noises;
    noises.push_back(identity_noise({0, -10, -10, -1}));
    noises.push_back(identity_noise({0, -400, -400, -10}));
    uint64_t seed = 101;
    for (size_t k = 0; k < noises.size(); ++k) {
        Dist state = random_dist(d, -30, 0);
        VectorXd u = random_unit(rng, d);
        std::vector<double> mr = row_major(state.m), mwr = row_major(noises[k].m), xs(n * d), ws(n * d);
        CHECK_OK(bingham_sample(d, mr.data(), state.z.data(), seed++, n, xs.data()));
        CHECK_OK(bingham_sample(d, mwr.data(), noises[k].z.data(), seed++, n, ws.data()));
        Eigen::Quaterniond qu(u(0), u(1), u(2), u(3));
        // fixed-size types: no heap allocation per sample (this loop runs under ASan and valgrind)
        Eigen::Matrix4d sum = Eigen::Matrix4d::Zero(), sum2 = Eigen::Matrix4d::Zero(), body = Eigen::Matrix4d::Zero();
        for (size_t i = 0; i < n; ++i) {
            const double *x = &xs[i * d], *w = &ws[i * d];
            Eigen::Quaterniond qx(x[0], x[1], x[2], x[3]), qw(w[0], w[1], w[2], w[3]);
            Eigen::Quaterniond q = qw * qu * qx, qb = qx * qu * qw;
            const Eigen::Vector4d y(q.w(), q.x(), q.y(), q.z()), yb(qb.w(), qb.x(), qb.y(), qb.z());
            const Eigen::Matrix4d yy = y * y.transpose();
            sum += yy;
            sum2 += yy.cwiseProduct(yy);
            body += yb * yb.transpose();
        }
        MatrixXd mean = sum / (double)n, var = sum2 / (double)n - mean.cwiseProduct(mean);
        body /= (double)n;
        bingham_filter *f = make_filter(state);
        CHECK_OK(bingham_filter_predict_world(f, u.data(), mwr.data(), noises[k].z.data()));
        MatrixXd S = second_moment(filter_state(f, d));
        int bad = 0;
        double worst = 0;
        for (int i = 0; i < d; ++i)
            for (int j = 0; j < d; ++j) {
                double se = std::sqrt(var(i, j) / (double)n), e = std::fabs(S(i, j) - mean(i, j));
                worst = std::max(worst, e / (se + 1e-300));
                if (e > 5 * se + 1e-12) ++bad;
            }
        CHECK(bad == 0);
        if (bad) fprintf(stderr, "    predict_world sampled, noise %d: worst %.2f standard errors\n", (int)k, worst);
        // the same samples composed in the body frame (x o u o w) are many standard errors away:
        // the check has the power to tell the frames apart
        double far = 0;
        for (int i = 0; i < d; ++i)
            for (int j = 0; j < d; ++j) far = std::max(far, std::fabs(S(i, j) - body(i, j)) / std::sqrt(var(i, j) / (double)n));
        CHECK(far > 20);
        bingham_filter_free(f);
    }
}

// d = 2: complex multiplication commutes, so the world frame is the body frame.
static void test_predict_world_2d() {
    const int d = 2;
    for (int rep = 0; rep < 6; ++rep) {
        Dist state = random_dist(d, -60, 0), noise = random_dist(d, -80, 0);
        VectorXd u = random_unit(rng, d);
        std::vector<double> mw = row_major(noise.m);
        bool with_u = rep % 3 != 0;
        bingham_filter *f = make_filter(state), *g = make_filter(state);
        CHECK_OK(bingham_filter_predict_world(f, with_u ? u.data() : NULL, mw.data(), noise.z.data()));
        if (with_u)
            CHECK_OK(bingham_filter_predict_rotation(g, u.data(), mw.data(), noise.z.data()));
        else
            CHECK_OK(bingham_filter_predict(g, mw.data(), noise.z.data()));
        Dist a = filter_state(f, d), b = filter_state(g, d);
        CHECK(exponent_difference(a, b) < 1e-12);
        report("predict_world vs predict_rotation", d, exponent_difference(a, b), 1e-12);
        MatrixXd A = second_moment(state), Y = with_u ? MatrixXd(left_matrix(u) * A * left_matrix(u).transpose()) : A;
        MatrixXd C = world_moment(second_moment(noise), Y);
        CHECK(max_abs(second_moment(a) - C) < 1e-10);
        report("predict_world", d, max_abs(second_moment(a) - C), 1e-10);
        bingham_filter_free(f);
        bingham_filter_free(g);
    }
}

// ---- update_world ----------------------------------------------------------------------------

static void test_update_world(int d) {
    for (int rep = 0; rep < 8; ++rep) {
        Dist state = random_dist(d, -25, 0);
        Dist noise = rep % 2 == 0 ? random_dist(d, -25, 0)
                                  : (d == 4 ? identity_noise({0, -400, -400, -10}) : identity_noise({0, -40}));
        VectorXd y = random_unit(rng, d);
        Dist lik = world_likelihood(y, noise);
        // the written-out likelihood is f_v(y o x^-1) up to a constant
        for (int t = 0; t < 5; ++t) {
            VectorXd x = random_unit(rng, d), v = compose_vectors(y, conjugate(x));
            double a = x.dot(exponent_matrix(lik.m, lik.z) * x), b = v.dot(exponent_matrix(noise.m, noise.z) * v);
            CHECK(std::fabs(a - b) < 1e-12 * std::max(1.0, noise.z.cwiseAbs().maxCoeff()));
        }
        bingham_filter *f = make_filter(state);
        std::vector<double> mv = row_major(noise.m);
        CHECK_OK(bingham_filter_update_world(f, y.data(), mv.data(), noise.z.data()));
        Dist post = filter_state(f, d);
        Dist ref = multiply(state, lik);
        CHECK(exponent_difference(post, ref) < 1e-10);
        report("update_world vs bingham_multiply", d, exponent_difference(post, ref), 1e-10);
        // independently of the library: the eigendecomposition of the summed exponents
        Eigen::SelfAdjointEigenSolver<MatrixXd> es(exponent_matrix(state.m, state.z) + exponent_matrix(lik.m, lik.z));
        VectorXd zref = es.eigenvalues().array() - es.eigenvalues()(d - 1);
        Dist eig{es.eigenvectors(), zref};
        CHECK(exponent_difference(post, eig) < 1e-10);
        CHECK(max_abs(post.z - zref) < 1e-10 * std::max(1.0, zref.cwiseAbs().maxCoeff()));
        // the sign of y does not matter
        VectorXd ny = -y;
        bingham_filter *g = make_filter(state);
        CHECK_OK(bingham_filter_update_world(g, ny.data(), mv.data(), noise.z.data()));
        CHECK(exponent_difference(filter_state(g, d), post) < 1e-12);
        // d = 4, anisotropic noise: not the body frame's likelihood (bingham_filter_update)
        if (d == 4 && rep % 2 == 1) {
            bingham_filter *h = make_filter(state);
            CHECK_OK(bingham_filter_update(h, y.data(), mv.data(), noise.z.data()));
            CHECK(exponent_difference(filter_state(h, d), post) > 1e-2);
            bingham_filter_free(h);
        }
        bingham_filter_free(g);
        bingham_filter_free(f);
    }
}

static void test_log_likelihood_world(int d) {
    for (int rep = 0; rep < 4; ++rep) {
        Dist state = random_dist(d, -15, 0);
        Dist noise = rep % 2 == 0 ? random_dist(d, -15, 0)
                                  : (d == 4 ? identity_noise({0, -15, -15, -2}) : identity_noise({0, -12}));
        VectorXd y = random_unit(rng, d);
        bingham_filter *f = make_filter(state);
        std::vector<double> mv = row_major(noise.m);
        double ll = 0;
        CHECK_OK(bingham_filter_log_likelihood_world(f, y.data(), mv.data(), noise.z.data(), &ll));
        CHECK_CLOSE(ll, world_log_likelihood_quadrature(state, noise, y), 1e-10);
        bingham_filter_free(f);
    }
}

// ---- the spin filter -------------------------------------------------------------------------

static void test_spin_step() {
    const MatrixXd D = conjugation(4);
    for (int rep = 0; rep < 12; ++rep) {
        Dist x = random_dist(4, -130, -5), v = random_dist(4, -50, -3);
        Dist w = rep % 3 == 0 ? identity_noise({0, -400, -400, -10}) : random_dist(4, -400, -1);
        Dist o = rep % 3 == 1 ? identity_noise({0, -40, -40, -10}) : random_dist(4, -60, -5);
        VectorXd u = random_unit(rng, 4), y = random_unit(rng, 4);
        bool observe = rep % 4 != 3, with_u = rep % 5 != 4;
        bingham_spin_filter *f = make_spin(x, v);
        std::vector<double> mw = row_major(w.m), mo = row_major(o.m);
        CHECK_OK(bingham_spin_filter_step(f, with_u ? u.data() : NULL, mw.data(), w.z.data(), observe ? y.data() : NULL,
                                          observe ? mo.data() : NULL, observe ? o.z.data() : NULL));
        SpinState got = spin_state(f);

        // the same step from the distribution functions
        Dist prior_x = compose(v, x);  // v o x
        Dist want_x = prior_x, v_post = v;
        if (observe) {
            Dist lik = world_likelihood(y, o);
            Dist x_inv{D * x.m, x.z};
            Dist g = compose(lik, x_inv);  // the evidence about v: a o b^-1
            want_x = multiply(prior_x, lik);
            v_post = multiply(v, g);
            // the evidence's moment, written with Eigen
            MatrixXd Eg = world_moment(second_moment(lik), D * second_moment(x) * D);
            CHECK(max_abs(second_moment(g) - Eg) < 1e-10);
        }
        Dist v_rot = with_u ? rotate_left(v_post, u) : v_post;
        Dist want_v = compose(w, v_rot);
        CHECK(exponent_difference(got.x, want_x) < 1e-9);
        report("spin step x", 4, exponent_difference(got.x, want_x), 1e-9);
        CHECK(exponent_difference(got.v, want_v) < 1e-9);
        report("spin step v", 4, exponent_difference(got.v, want_v), 1e-9);
        // the compositions' second moments against Eigen
        if (!observe) {
            MatrixXd Ex = world_moment(second_moment(v), second_moment(x));
            CHECK(max_abs(second_moment(got.x) - Ex) < 1e-10);
            report("spin predicted x moment", 4, max_abs(second_moment(got.x) - Ex), 1e-10);
        }
        MatrixXd Ar = second_moment(v_post);
        if (with_u) Ar = left_matrix(u) * Ar * left_matrix(u).transpose();
        MatrixXd Ev = world_moment(second_moment(w), Ar);
        CHECK(max_abs(second_moment(got.v) - Ev) < 1e-10);
        report("spin v moment", 4, max_abs(second_moment(got.v) - Ev), 1e-10);
        // modes: the last columns
        double q[4];
        CHECK_OK(bingham_spin_filter_orientation_mode(f, q));
        CHECK(angle(Eigen::Map<VectorXd>(q, 4), want_x.m.col(3)) < 1e-6);
        CHECK_OK(bingham_spin_filter_spin_mode(f, q));
        CHECK(angle(Eigen::Map<VectorXd>(q, 4), want_v.m.col(3)) < 1e-6);
        bingham_spin_filter_free(f);
    }
}

static void test_spin_log_likelihood() {
    for (int rep = 0; rep < 3; ++rep) {
        Dist x = random_dist(4, -25, -2), v = random_dist(4, -20, -2);
        Dist o = rep == 0 ? identity_noise({0, -12, -12, -3}) : random_dist(4, -15, -1);
        VectorXd y = random_unit(rng, 4);
        bingham_spin_filter *f = make_spin(x, v);
        std::vector<double> mo = row_major(o.m);
        double ll = 0;
        CHECK_OK(bingham_spin_filter_log_likelihood(f, y.data(), mo.data(), o.z.data(), &ll));
        CHECK_CLOSE(ll, world_log_likelihood_quadrature(compose(v, x), o, y), 1e-8);
        bingham_spin_filter_free(f);
    }
}

static void test_spin_converges() {
    for (int trial = 0; trial < 4; ++trial) {
        VectorXd axis = random_unit(rng, 3);
        double rate = 0.3 + 1.2 * std::uniform_real_distribution<double>(0, 1)(rng);  // rad per step
        Eigen::Quaterniond s(Eigen::AngleAxisd(rate, Eigen::Vector3d(axis(0), axis(1), axis(2))));
        VectorXd spin(4);
        spin << s.w(), s.x(), s.y(), s.z();
        VectorXd x = random_unit(rng, 4);
        Dist uniform{MatrixXd::Identity(4, 4), VectorXd::Zero(4)};
        bingham_spin_filter *f = make_spin(uniform, identity_noise({0, -3, -3, -3}));
        Dist w = identity_noise({0, -400, -400, -400}), o = identity_noise({0, -400, -400, -400});
        std::vector<double> mw = row_major(w.m), mo = row_major(o.m);
        double err = 0, x_err = 0, err20 = 0;
        for (int k = 0; k < 300; ++k) {
            VectorXd y = (k % 3 == 1) ? VectorXd(-x) : x;  // the sign of an observation does not matter
            CHECK_OK(bingham_spin_filter_step(f, NULL, mw.data(), w.z.data(), y.data(), mo.data(), o.z.data()));
            double q[4];
            CHECK_OK(bingham_spin_filter_spin_mode(f, q));
            err = angle(Eigen::Map<VectorXd>(q, 4), spin);
            if (k == 19) err20 = err;
            CHECK_OK(bingham_spin_filter_orientation_mode(f, q));
            x_err = angle(Eigen::Map<VectorXd>(q, 4), x);
            x = compose_vectors(spin, x);
        }
        CHECK(err < 1e-6);
        CHECK(x_err < 1e-6);
        if (!(err < 1e-6 && x_err < 1e-6))
            fprintf(stderr, "    trial %d: spin error %.3g (after 20 steps %.3g), orientation error %.3g\n", trial, err,
                    err20, x_err);
        // the spreads: 2 sqrt(omega_i) along the columns, 2 sqrt(1 - omega_3) in total, omega from
        // the marginals' second moments; the spin's far below the prior's, not below the noise's
        double xs[4], vs[4], prior[4], noise[4];
        CHECK_OK(bingham_spin_filter_angular_spread(f, xs, vs));
        SpinState st = spin_state(f);
        const Dist *marg[2] = {&st.x, &st.v};
        const double *spreads[2] = {xs, vs};
        for (int k = 0; k < 2; ++k) {
            MatrixXd S = second_moment(*marg[k]);
            for (int i = 0; i < 3; ++i)
                CHECK_CLOSE(spreads[k][i], 2 * std::sqrt(marg[k]->m.col(i).dot(S * marg[k]->m.col(i))), 1e-9);
            CHECK_CLOSE(spreads[k][3], 2 * std::sqrt(1 - marg[k]->m.col(3).dot(S * marg[k]->m.col(3))), 1e-9);
        }
        Dist p = identity_noise({0, -3, -3, -3});
        std::vector<double> pm = row_major(p.m);
        CHECK_OK(bingham_angular_spread(4, pm.data(), p.z.data(), prior));
        CHECK_OK(bingham_angular_spread(4, mw.data(), w.z.data(), noise));
        CHECK(vs[3] >= noise[3] && vs[3] < prior[3] / 5);
        bingham_spin_filter_free(f);
    }
}

int main() {
    test_predict_world_exact();
    test_predict_world_sampled();
    test_predict_world_2d();
    for (int d = 2; d <= 4; d += 2) {
        test_update_world(d);
        test_log_likelihood_world(d);
    }
    test_spin_step();
    test_spin_log_likelihood();
    test_spin_converges();
    return check_summary("world_eigen");
}
