// standards: c++17 c++20
//
// The Eigen side of the C++ wrapper (include/bingham_eigen.hpp), against the explicit C calls
// and against computations written here with Eigen:
//
// - Eigen::Quaterniond in: Filter::update / predict_rotation / log_likelihood and pdf with a
//   random Eigen::Quaterniond give bit for bit what the C calls give with (q.w(), q.x(), q.y(),
//   q.z()) -- and something else than with Eigen's coeffs() order (x, y, z, w), so the test
//   would notice a wrapper that used coeffs();
// - Eigen::Quaterniond out: Filter::mode_quaternion() and Ahrs::quaternion() converted to
//   Eigen::Quaterniond have w() = the C mode's entry 0, x() = entry 1, ...; a static sensor at
//   a known orientation q_true (accelerometer R(q_true)^T g, magnetometer R(q_true)^T m, with
//   R from Eigen) drives the AHRS to q_true (Eigen's angularDistance < 0.5 degrees);
// - Ahrs::gyro_bias_covariance_matrix(): entry (i, j) is the C call's row-major cov[3 i + j],
//   symmetric with a positive diagonal; bias_std^2 * I on creation;
// - M in either storage order: a column-major Matrix4d and a row-major
//   Matrix<double, 4, 4, RowMajor> with the same entries give the same Distribution (the
//   row-major std::vector equal to the entries M(i, j)) and the same results; the transpose gives
//   a different one; Distribution::matrix() gives M back; second_moment_matrix equals
//   M diag(omega) M^T computed with Eigen from the gradient of log F;
// - pdf at Eigen points (a vector, an n x 4 matrix in either storage order) equals the C call
//   and exp(x^T M Z M^T x) / F computed with Eigen;
// - vector_observation with Eigen 3-vectors: the exponent q^T M Z M^T q equals
//   kappa (r^T R(q) b - 1) for random q, R(q) = Eigen::Quaterniond(q).toRotationMatrix();
// - mle of an Eigen matrix in either storage order equals mle of the row-major vector;
// - the world-frame steps with Eigen quaternions: bit for bit the C calls with (w, x, y, z) (and
//   not with coeffs()); the prediction's second moment equals sum_ab B_ab L_a S L_b^T computed
//   with Eigen (S the second moment of u x, B the noise's, L_a the left-multiplication matrices
//   built from Eigen's quaternion product), the update equals bingham::multiply with the
//   likelihood's directions conj(m_i) y computed with Eigen;
// - SpinFilter with Eigen quaternions in and out: bit for bit the C calls; its predictive
//   density equals the first-order filter's world-frame one for the prior compose(spin,
//   orientation); a noiseless constant spin (x[k+1] = spin * x[k] with Eigen) is found
//   (spin_mode().angularDistance(spin) < 1e-6 after 300 steps).
// - Filter::surprise with an Eigen::Quaterniond equals the C call with (w, x, y, z);
// - Ahrs::update_batch with `spread` and `health` (with and without the magnetometer, health
//   without spread): row k equals health().score and uncertainty() after the same samples fed
//   one by one through the Eigen update().
// - Ahrs::orientation_covariance_matrix(): entry (i, j) is the C call's row-major oc[3 i + j],
//   symmetric with eigenvalues >= 0 (Eigen's solver), trace uncertainty()^2, the identity before
//   the first sample; in the world frame: for the tilted static sensor without magnetometer the
//   eigenvector of the largest eigenvalue (the unknown heading) is world z, not the sensor's z
//   axis R(q_true) e_z;
// - Ahrs::update_dt with Eigen 3-vectors equals the std::array overload bit for bit; the timed
//   Eigen batch (timestamps a column or a row vector) equals the std::vector one, row k's spread
//   and health equal uncertainty() and health().score after the same samples fed as timed
//   batches of one; a size mismatch throws BINGHAM_ERR_INVALID_DIMENSION, a timestamp before the
//   previous one BINGHAM_ERR_INVALID_ARGUMENT naming "sample 5".
#include <Eigen/Dense>

#include "bingham_eigen.hpp"

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "check.h"

static_assert(BINGHAM_HPP_EIGEN, "Eigen support must be detected");
static_assert(std::is_convertible_v<Eigen::Quaterniond, bingham::Quaternion> &&
                  std::is_convertible_v<bingham::Quaternion, Eigen::Quaterniond>,
              "Quaternion <-> Eigen::Quaterniond");

using Eigen::Matrix4d;
using Eigen::Quaterniond;
using Eigen::Vector3d;
using Eigen::Vector4d;
using RowMatrix4d = Eigen::Matrix<double, 4, 4, Eigen::RowMajor>;

static std::mt19937_64 rng(20251124);

static Quaterniond random_quaternion() {
    std::normal_distribution<double> g;
    Quaterniond q(g(rng), g(rng), g(rng), g(rng));
    q.normalize();
    if (q.w() < 0) q.coeffs() *= -1;
    return q;
}

static Matrix4d random_orthogonal() {
    std::normal_distribution<double> g;
    Matrix4d a;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) a(i, j) = g(rng);
    Eigen::HouseholderQR<Matrix4d> qr(a);
    return qr.householderQ() * Matrix4d::Identity();
}

static bool same(const std::vector<double> &a, const std::vector<double> &b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}
static bool same(const bingham::Distribution &a, const bingham::Distribution &b) {
    return a.d == b.d && same(a.M, b.M) && same(a.z, b.z);
}

static void test_quaternions() {
    const bingham::Distribution w = bingham::noise_from_angle_std_deg(4, 2.0);
    const bingham::Distribution v = bingham::noise_from_angle_std_deg(4, 4.0);
    const bingham::Distribution init(Matrix4d::Identity(), Vector4d(-1, -1, -1, 0));
    bingham::Filter f(init);
    bingham::Filter wrong = f.clone();  // what coeffs() order would give
    bingham_filter *c = nullptr;
    CHECK_OK(bingham_filter_new(4, init.M.data(), init.z.data(), &c));
    for (int k = 0; k < 20; ++k) {
        const Quaterniond u = random_quaternion(), meas = random_quaternion();
        f.predict_rotation(u, w);
        f.update(meas, v);
        const double uc[4] = {u.w(), u.x(), u.y(), u.z()}, mc[4] = {meas.w(), meas.x(), meas.y(), meas.z()};
        CHECK_OK(bingham_filter_predict_rotation(c, uc, w.M.data(), w.z.data()));
        CHECK_OK(bingham_filter_update(c, mc, v.M.data(), v.z.data()));
        CHECK_OK(bingham_filter_predict_rotation(wrong.get(), u.coeffs().data(), w.M.data(), w.z.data()));
        CHECK_OK(bingham_filter_update(wrong.get(), meas.coeffs().data(), v.M.data(), v.z.data()));
        double ll_c;
        CHECK_OK(bingham_filter_log_likelihood(c, mc, v.M.data(), v.z.data(), &ll_c));
        CHECK(f.log_likelihood(meas, v) == ll_c);
        double s_c = -1;
        CHECK_OK(bingham_filter_surprise(c, mc, v.M.data(), v.z.data(), &s_c));
        CHECK(f.surprise(meas, v) == s_c);
    }
    double m[16], z[4], mode[4];
    CHECK_OK(bingham_filter_get_state(c, m, z));
    CHECK_OK(bingham_filter_mode(c, mode));
    const bingham::Distribution s = f.state();
    CHECK(std::memcmp(s.M.data(), m, sizeof m) == 0 && std::memcmp(s.z.data(), z, sizeof z) == 0);
    CHECK(!same(s, wrong.state()));  // the order matters: a coeffs() wrapper would fail above
    const Quaterniond q = f.mode_quaternion();
    CHECK(q.w() == mode[0] && q.x() == mode[1] && q.y() == mode[2] && q.z() == mode[3]);
    const bingham::Quaternion bq = q;
    CHECK(bq.w == q.w() && bq.x == q.x() && bq.y == q.y() && bq.z == q.z());
    // Eigen::Map<Quaterniond> over Eigen's own (x, y, z, w) storage converts by name too
    const double xyzw[4] = {0.5, -0.5, 0.5, 0.5};
    const bingham::Quaternion mq = Eigen::Map<const Quaterniond>(xyzw);
    CHECK(mq.w == 0.5 && mq.x == 0.5 && mq.y == -0.5 && mq.z == 0.5);
    // mode of a distribution, pdf at quaternions, rotate
    const Quaterniond dm = bingham::mode_quaternion(s);
    CHECK(dm.w() == mode[0] && dm.z() == mode[3]);
    const Quaterniond p = random_quaternion();
    double pdf_c;
    const double pc[4] = {p.w(), p.x(), p.y(), p.z()};
    CHECK_OK(bingham_pdf(4, m, z, 1, pc, &pdf_c));
    CHECK(bingham::pdf(s, p) == pdf_c);
    double rm[16], rz[4];
    CHECK_OK(bingham_rotate_left(4, m, z, pc, rm, rz));
    const bingham::Distribution rl = bingham::rotate_left(s, p);
    CHECK(std::memcmp(rl.M.data(), rm, sizeof rm) == 0);
    bingham_filter_free(c);
}

static void test_storage_order() {
    const Matrix4d mc = random_orthogonal();  // column-major
    const RowMatrix4d mr = mc;                 // the same entries, row-major storage
    const Vector4d z(-40, -9, -2, 0);
    const bingham::Distribution a(mc, z), b(mr, z);
    CHECK(same(a, b));
    bool entries = true;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) entries = entries && a.M[static_cast<std::size_t>(4 * i + j)] == mc(i, j);
    CHECK(entries);
    CHECK(!same(a, bingham::Distribution(mc.transpose(), z)));
    CHECK(a.matrix() == mc && a.concentrations() == z);
    // second moment: library vs M diag(omega) M^T with Eigen
    const auto lg = bingham::log_normalization_constant_gradient({z(0), z(1), z(2), z(3)});
    const Vector4d omega(lg.gradient[0], lg.gradient[1], lg.gradient[2], lg.gradient[3]);
    const Matrix4d s_ref = mc * omega.asDiagonal() * mc.transpose();
    const Eigen::MatrixXd s_lib = bingham::second_moment_matrix(a);
    CHECK((s_lib - s_ref).cwiseAbs().maxCoeff() < 1e-14);
    CHECK(bingham::second_moment_matrix(b) == s_lib);
    // MLE of an Eigen matrix in either order
    const RowMatrix4d s_row = s_lib;
    const bingham::Distribution fit = bingham::mle(s_lib), fit_r = bingham::mle(s_row);
    std::vector<double> sv(16);
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) sv[static_cast<std::size_t>(4 * i + j)] = s_lib(i, j);
    CHECK(same(fit, fit_r) && same(fit, bingham::mle(4, sv)));
    CHECK_CLOSE(fit.z[0], -40.0, 1e-7);
    // pdf: Eigen points against the C call and an Eigen computation
    Eigen::Matrix<double, 6, 4> pts;  // column-major n x d
    for (int k = 0; k < 6; ++k) pts.row(k) = random_quaternion().coeffs().transpose();  // any unit vectors
    const Eigen::Matrix<double, 6, 4, Eigen::RowMajor> pts_r = pts;
    std::vector<double> flat(24), p_c(6);
    for (int k = 0; k < 6; ++k)
        for (int j = 0; j < 4; ++j) flat[static_cast<std::size_t>(4 * k + j)] = pts(k, j);
    CHECK_OK(bingham_pdf(4, a.M.data(), a.z.data(), 6, flat.data(), p_c.data()));
    const Eigen::VectorXd pa = bingham::pdf_points(a, pts), pb = bingham::pdf_points(a, pts_r);
    const double log_f = bingham::log_normalization_constant({z(0), z(1), z(2), z(3)});
    for (int k = 0; k < 6; ++k) {
        CHECK(pa(k) == p_c[static_cast<std::size_t>(k)] && pb(k) == pa(k));
        const Vector4d x = pts.row(k).transpose();
        CHECK_CLOSE(pa(k), std::exp(x.dot(mc * z.asDiagonal() * mc.transpose() * x) - log_f), 1e-12);
        CHECK(bingham::pdf(a, x) == pa(k));
        CHECK_CLOSE(bingham::log_pdf(a, x), std::log(pa(k)), 1e-12);
    }
    // a 2 x 2 matrix too
    const Eigen::Matrix2d m2 = Eigen::Rotation2Dd(0.3).toRotationMatrix();
    const bingham::Distribution d2(m2, Eigen::Vector2d(-5, 0));
    CHECK(d2.d == 2 && d2.M[1] == m2(0, 1) && d2.M[2] == m2(1, 0));
    // wrong sizes throw
    try {
        const bingham::Distribution bad(Eigen::Matrix3d::Identity(), z);
        CHECK(false);
    } catch (const bingham::Error &e) {
        CHECK(e.status() == BINGHAM_ERR_INVALID_DIMENSION);
    }
    // samples as an Eigen matrix: the same as the vector version
    const Eigen::MatrixXd smp = bingham::sample_matrix(a, 3, 7);
    const std::vector<double> sv2 = bingham::sample(a, 3, 7);
    CHECK(smp.rows() == 3 && smp.cols() == 4 && smp(1, 2) == sv2[6] && smp(2, 3) == sv2[11]);
}

static void test_vectors() {
    // vector_observation with Eigen vectors: exponent q^T M Z M^T q = kappa (r^T R(q) b - 1)
    std::normal_distribution<double> g;
    const Vector3d body = Vector3d(g(rng), g(rng), g(rng)).normalized();
    const Vector3d ref = Vector3d(g(rng), g(rng), g(rng)).normalized();
    const double kappa = 25.0;
    const bingham::Distribution obs = bingham::vector_observation(body, ref, kappa);
    CHECK(same(obs, bingham::vector_observation(std::array<double, 3>{body(0), body(1), body(2)},
                                                std::array<double, 3>{ref(0), ref(1), ref(2)}, kappa)));
    const Matrix4d m = obs.matrix();
    const Vector4d z = obs.concentrations();
    double worst = 0;
    for (int k = 0; k < 50; ++k) {
        const Quaterniond q = random_quaternion();
        const Vector4d qv(q.w(), q.x(), q.y(), q.z());
        const double exponent = qv.dot(m * z.asDiagonal() * m.transpose() * qv);
        const double direct = kappa * (ref.dot(q.toRotationMatrix() * body) - 1.0);
        worst = std::max(worst, std::abs(exponent - direct));
    }
    CHECK(worst < 1e-12);
    // Filter::update_vector with Eigen vectors equals the array version
    bingham::Filter f(bingham::noise_from_angle_std_deg(4, 30.0));
    bingham::Filter h = f.clone();
    f.update_vector(body, ref, kappa);
    h.update_vector({body(0), body(1), body(2)}, {ref(0), ref(1), ref(2)}, kappa);
    CHECK(same(f.state(), h.state()));
    CHECK(f.log_likelihood_vector(body, ref, kappa) ==
          h.log_likelihood_vector({body(0), body(1), body(2)}, {ref(0), ref(1), ref(2)}, kappa));
}

static void test_ahrs() {
    // a static sensor at q_true: the AHRS converges to it (sensor -> world, ENU)
    const Quaterniond q_true = Quaterniond(Eigen::AngleAxisd(0.7, Vector3d(0.2, -0.5, 1.0).normalized()));
    const Eigen::Matrix3d r = q_true.toRotationMatrix();
    const Vector3d g_world(0, 0, 9.81), m_world(0, 20.0, -40.0);
    const Vector3d acc = r.transpose() * g_world, mag = r.transpose() * m_world;
    bingham::Ahrs a(0.01), b(0.01);
    for (int k = 0; k < 300; ++k) {
        a.update(Vector3d::Zero(), acc, mag);
        b.update({0, 0, 0}, {acc(0), acc(1), acc(2)}, {mag(0), mag(1), mag(2)});
    }
    // `auto` is an Eigen::Quaterniond where Eigen is enabled (issue 23)
    auto qa = a.quaternion();
    static_assert(std::is_same<decltype(qa), Eigen::Quaterniond>::value, "Ahrs::quaternion() is Eigen");
    static_assert(std::is_same<decltype(bingham::Filter(bingham::noise_from_angle_std_deg(4, 1.0)).mode_quaternion()),
                               Eigen::Quaterniond>::value,
                  "Filter::mode_quaternion() is Eigen");
    CHECK(qa.angularDistance(q_true) < 0.01);
    const Quaterniond q = a.quaternion();
    double qc[4];
    CHECK_OK(bingham_ahrs_quaternion(a.get(), qc));
    CHECK(q.w() == qc[0] && q.x() == qc[1] && q.y() == qc[2] && q.z() == qc[3]);
    CHECK(same(a.state(), b.state()));
    const double err_deg = q.angularDistance(q_true) * 180.0 / 3.14159265358979323846;
    if (err_deg >= 0.5) std::fprintf(stderr, "    AHRS error %.3f deg\n", err_deg);
    CHECK(err_deg < 0.5);
    CHECK((a.gyro_bias_vector() - Vector3d(b.gyro_bias()[0], b.gyro_bias()[1], b.gyro_bias()[2])).norm() == 0);
    {
        // the scale estimate as an Eigen vector: entry i = the array's (and the C call's) entry
        // i, after a turning stream that moves it off zero
        bingham::Ahrs s(0.01);
        for (int k = 0; k < 200; ++k)
            s.update(Vector3d(0.1, -0.05, 0.2 * std::sin(0.1 * k)), Vector3d(0.3, -0.2, 9.7), Vector3d(0.1, 20.0, -40.0));
        const Vector3d sv = s.gyro_scale_vector();
        double sc[3];
        CHECK_OK(bingham_ahrs_gyro_scale(s.get(), sc));
        CHECK(sv(0) == sc[0] && sv(1) == sc[1] && sv(2) == sc[2]);
        CHECK(sv.norm() > 0.0);
    }
    // the bias covariance as Eigen::Matrix3d: entry (i, j) = the C call's cov[3 i + j]
    const Eigen::Matrix3d cov = a.gyro_bias_covariance_matrix();
    double cc[9];
    CHECK_OK(bingham_ahrs_gyro_bias_covariance(a.get(), cc));
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) CHECK(cov(i, j) == cc[3 * i + j]);
    // the Eigen batch (n x 3 in, n x 4 out, the spreads) equals the vector batch and the
    // per-sample spread
    {
        const int n = 50;
        Eigen::MatrixXd gm(n, 3), am(n, 3), mm(n, 3);  // column-major in: any storage order
        std::vector<double> gv, av, mv;
        for (int k = 0; k < n; ++k) {
            const Vector3d gk(0.01 * k, -0.02, 0.03);
            gm.row(k) = gk.transpose();
            am.row(k) = acc.transpose();
            mm.row(k) = mag.transpose();
            for (int c = 0; c < 3; ++c) {
                gv.push_back(gk(c));
                av.push_back(acc(c));
                mv.push_back(mag(c));
            }
        }
        bingham::Ahrs c1 = a.clone(), c2 = a.clone(), c3 = a.clone();
        Eigen::VectorXd spread;
        const auto qe = c1.update_batch(gm, am, mm, &spread);
        const std::vector<double> qv = c2.update_batch(gv, av, mv);
        CHECK(qe.rows() == n && qe.cols() == 4 && spread.size() == n);
        bool same_q = true;
        for (int k = 0; k < n; ++k)
            for (int c = 0; c < 4; ++c) same_q = same_q && qe(k, c) == qv[4 * k + c];
        CHECK(same_q);
        CHECK(spread(n - 1) == c1.uncertainty());
        // with the health scores (and the spreads): each row equals health().score and
        // uncertainty() after the same samples one by one
        {
            bingham::Ahrs h1 = a.clone(), h2 = a.clone(), one = a.clone(), one_nomag = a.clone();
            Eigen::VectorXd sp1, hs1, sp2, hs2;
            const auto qh = h1.update_batch(gm, am, mm, &sp1, &hs1);
            const auto qh2 = h2.update_batch(gm, am, &sp2, &hs2);  // without the magnetometer
            CHECK(qh.rows() == n && sp1.size() == n && hs1.size() == n && qh2.rows() == n && sp2.size() == n &&
                  hs2.size() == n);
            bool q_ok = true, sp_ok = true, h_ok = true, q2_ok = true, sp2_ok = true, h2_ok = true;
            for (int k = 0; k < n; ++k) {
                one.update(Vector3d(gm.row(k).transpose()), Vector3d(am.row(k).transpose()),
                           Vector3d(mm.row(k).transpose()));
                one_nomag.update(Vector3d(gm.row(k).transpose()), Vector3d(am.row(k).transpose()));
                const Quaterniond q1 = one.quaternion(), q2 = one_nomag.quaternion();
                q_ok = q_ok && qh(k, 0) == q1.w() && qh(k, 1) == q1.x() && qh(k, 2) == q1.y() && qh(k, 3) == q1.z();
                sp_ok = sp_ok && sp1(k) == one.uncertainty();
                h_ok = h_ok && hs1(k) == one.health().score;
                q2_ok = q2_ok && qh2(k, 0) == q2.w() && qh2(k, 1) == q2.x() && qh2(k, 2) == q2.y() &&
                        qh2(k, 3) == q2.z();
                sp2_ok = sp2_ok && sp2(k) == one_nomag.uncertainty();
                h2_ok = h2_ok && hs2(k) == one_nomag.health().score;
            }
            CHECK(q_ok && sp_ok && h_ok);
            CHECK(q2_ok && sp2_ok && h2_ok);
            CHECK(hs1.allFinite() && hs1.minCoeff() >= 0 && hs1(n - 1) == h1.health().score);
            // the score from the C readout of the same handle
            bingham_ahrs_health_report hc;
            CHECK_OK(bingham_ahrs_health(h1.get(), &hc));
            CHECK(hc.score == hs1(n - 1) && hc.has_mag_reference == 1);
            // health alone (no spread): the same scores
            bingham::Ahrs h3 = a.clone();
            Eigen::VectorXd hs3;
            const auto qh3 = h3.update_batch(gm, am, mm, nullptr, &hs3);
            CHECK(qh3 == qh && hs3 == hs1);
        }
        const auto q6 = c3.update_batch(gm, am);  // without the magnetometer
        CHECK(q6.rows() == n);
        bool threw = false;
        try {
            (void)c3.update_batch(gm, Eigen::MatrixXd(n - 1, 3));
        } catch (const bingham::Error &e) {
            threw = e.status() == BINGHAM_ERR_INVALID_DIMENSION;
        }
        CHECK(threw);
    }
    CHECK((cov - cov.transpose()).norm() <= 1e-12 * cov.norm() && cov.diagonal().minCoeff() > 0);
    // the orientation covariance as Eigen::Matrix3d: entry (i, j) = the C call's oc[3 i + j];
    // symmetric, positive semi-definite, its trace uncertainty()^2; the identity before a sample
    {
        const Eigen::Matrix3d oc = a.orientation_covariance_matrix();
        double occ[9];
        CHECK_OK(bingham_ahrs_orientation_covariance(a.get(), occ));
        bool same_oc = true;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) same_oc = same_oc && oc(i, j) == occ[3 * i + j];
        CHECK(same_oc && oc == oc.transpose());
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(oc);
        CHECK(es.eigenvalues().minCoeff() >= -1e-15 * oc.trace());
        CHECK_CLOSE(oc.trace(), a.uncertainty() * a.uncertainty(), 1e-12);
        CHECK(bingham::Ahrs(0.01).orientation_covariance_matrix() == Eigen::Matrix3d::Identity());
    }
    // in the world frame: the same tilted sensor without a magnetometer has an unknown heading,
    // the variance about world z (up), not about the sensor's z axis R(q_true) e_z
    {
        bingham::Ahrs six(0.01);
        for (int k = 0; k < 300; ++k) six.update(Vector3d::Zero(), acc);
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(six.orientation_covariance_matrix());
        const Vector3d top = es.eigenvectors().col(2);  // eigenvalues ascending
        const double along_up = std::abs(top.dot(Vector3d::UnitZ())), along_sensor_z = std::abs(top.dot(r.col(2)));
        if (!(along_up > 1.0 - 1e-6 && es.eigenvalues()(2) > 1e3 * es.eigenvalues()(1)))
            std::fprintf(stderr, "    6-D: top eigenvector . up = %.9f, eigenvalues %g %g %g\n", along_up,
                         es.eigenvalues()(0), es.eigenvalues()(1), es.eigenvalues()(2));
        CHECK(along_up > 1.0 - 1e-6 && es.eigenvalues()(2) > 1e3 * es.eigenvalues()(1));
        CHECK(along_sensor_z < 0.99);  // (the tilt is large enough to tell the two apart)
    }
    // update_dt with Eigen vectors: the std::array overload's result, bit for bit; the timed
    // Eigen batch (timestamps as a column or a row vector, any storage order of the rows) equals
    // the std::vector one and the per-sample spread and health; sizes checked
    {
        bingham::Ahrs e1 = a.clone(), e2 = a.clone();
        for (int k = 0; k < 20; ++k) {
            const Vector3d gk(0.01 * k, -0.02, k % 7 == 3 ? std::nan("") : 0.03);
            const double h = 0.01 * (1.0 + 0.25 * std::sin(0.9 * k));
            if (k % 2) {
                e1.update_dt(h, gk, acc, mag);
                e2.update_dt(h, {gk(0), gk(1), gk(2)}, {acc(0), acc(1), acc(2)}, {mag(0), mag(1), mag(2)});
            } else {
                e1.update_dt(h, gk, acc);
                e2.update_dt(h, {gk(0), gk(1), gk(2)}, {acc(0), acc(1), acc(2)});
            }
        }
        CHECK(same(e1.state(), e2.state()) && e1.orientation_covariance() == e2.orientation_covariance());
        const int n = 40;
        Eigen::MatrixXd gm(n, 3), am(n, 3), mm(n, 3);
        Eigen::VectorXd tc(n);
        std::vector<double> tv, gv, av, mv;
        double tk = 3.0;
        for (int k = 0; k < n; ++k) {
            tk += 0.01 * (1.0 + 0.4 * std::sin(1.1 * k)) + (k % 13 == 12 ? 0.03 : 0.0);
            tc(k) = tk;
            tv.push_back(tk);
            const Vector3d gk(0.2 * std::sin(0.2 * k), k % 9 == 4 ? std::nan("") : -0.02, 0.03);
            gm.row(k) = gk.transpose();
            am.row(k) = acc.transpose();
            mm.row(k) = mag.transpose();
            for (int c = 0; c < 3; ++c) {
                gv.push_back(gk(c));
                av.push_back(acc(c));
                mv.push_back(mag(c));
            }
        }
        bingham::Ahrs t1 = e1.clone(), t2 = e1.clone(), t3 = e1.clone(), one = e1.clone();
        Eigen::VectorXd sp, hs;
        const auto q1 = t1.update_batch(tc, gm, am, mm, &sp, &hs);
        const Eigen::RowVectorXd tr = tc.transpose();
        const auto q3 = t3.update_batch(tr, gm, am, mm);
        const std::vector<double> q2 = t2.update_batch(tv, gv, av, mv);
        CHECK(q1.rows() == n && sp.size() == n && hs.size() == n && q3 == q1);
        bool q_ok = true, row_ok = true;
        for (int k = 0; k < n; ++k) {
            for (int c = 0; c < 4; ++c) q_ok = q_ok && q1(k, c) == q2[static_cast<std::size_t>(4 * k + c)];
            const std::vector<double> tk1 = {tv[static_cast<std::size_t>(k)]};
            (void)one.update_batch(tk1, {gv[3 * k], gv[3 * k + 1], gv[3 * k + 2]}, {av[3 * k], av[3 * k + 1], av[3 * k + 2]},
                                   {mv[3 * k], mv[3 * k + 1], mv[3 * k + 2]});
            row_ok = row_ok && sp(k) == one.uncertainty() && hs(k) == one.health().score;
        }
        CHECK(q_ok && row_ok && same(t1.state(), t2.state()) && same(t1.state(), one.state()));
        bool threw = false;
        try {
            (void)t1.update_batch(Eigen::VectorXd(n - 1), gm, am, mm);
        } catch (const bingham::Error &e) {
            threw = e.status() == BINGHAM_ERR_INVALID_DIMENSION;
        }
        CHECK(threw);
        // a timestamp before the previous one: the C status, "sample k", the rows before done
        threw = false;
        Eigen::VectorXd tb = tc.array() + (tc(n - 1) - tc(0) + 0.01);  // after t1's last timestamp
        tb(5) = tb(4) - 0.01;
        try {
            (void)t1.update_batch(tb, gm, am, mm);
        } catch (const bingham::Error &e) {
            threw = e.status() == BINGHAM_ERR_INVALID_ARGUMENT &&
                    std::string(e.what()).find("sample 5") != std::string::npos;
        }
        CHECK(threw);
    }
    const double bias_std = bingham::ahrs_default_params(0.01).bias_std;
    CHECK(bingham::Ahrs(0.01).gyro_bias_covariance_matrix() == Eigen::Matrix3d::Identity() * (bias_std * bias_std));
    CHECK(a.uncertainty() > 0 && a.uncertainty() < 0.1);
}

// The 4 x 4 matrix of q * (.) (Hamilton product, scalar first), from Eigen's product.
static Matrix4d left_matrix(const Quaterniond &q) {
    Matrix4d l;
    for (int j = 0; j < 4; ++j) {
        Vector4d e = Vector4d::Zero();
        e(j) = 1;
        const Quaterniond p = q * Quaterniond(e(0), e(1), e(2), e(3));
        l.col(j) = Vector4d(p.w(), p.x(), p.y(), p.z());
    }
    return l;
}
static Quaterniond quat(const Vector4d &wxyz) { return Quaterniond(wxyz(0), wxyz(1), wxyz(2), wxyz(3)); }
static Matrix4d precision(const bingham::Distribution &b) {
    return b.matrix() * b.concentrations().asDiagonal() * b.matrix().transpose();
}

static void test_world_steps() {
    const bingham::Distribution init(random_orthogonal(), Vector4d(-60, -25, -8, 0));
    const bingham::Distribution w(random_orthogonal(), Vector4d(-400, -200, -50, 0));
    const bingham::Distribution v(random_orthogonal(), Vector4d(-40, -40, -10, 0));
    bingham::Filter f(init), wrong(init);
    bingham_filter *c = nullptr;
    CHECK_OK(bingham_filter_new(4, init.M.data(), init.z.data(), &c));
    for (int k = 0; k < 10; ++k) {
        const Quaterniond u = random_quaternion(), y = random_quaternion();
        const double uc[4] = {u.w(), u.x(), u.y(), u.z()}, yc[4] = {y.w(), y.x(), y.y(), y.z()};
        f.predict_world(u, w);
        CHECK_OK(bingham_filter_predict_world(c, uc, w.M.data(), w.z.data()));
        CHECK_OK(bingham_filter_predict_world(wrong.get(), u.coeffs().data(), w.M.data(), w.z.data()));
        double ll;
        CHECK_OK(bingham_filter_log_likelihood_world(c, yc, v.M.data(), v.z.data(), &ll));
        CHECK(f.log_likelihood_world(y, v) == ll);
        f.update_world(y, v);
        CHECK_OK(bingham_filter_update_world(c, yc, v.M.data(), v.z.data()));
        CHECK_OK(bingham_filter_update_world(wrong.get(), y.coeffs().data(), v.M.data(), v.z.data()));
    }
    double m[16], z[4];
    CHECK_OK(bingham_filter_get_state(c, m, z));
    const bingham::Distribution s = f.state();
    CHECK(std::memcmp(s.M.data(), m, sizeof m) == 0 && std::memcmp(s.z.data(), z, sizeof z) == 0);
    CHECK(!same(s, wrong.state()));

    // prediction: the second moment of w * u * x, written with Eigen
    const Quaterniond u = random_quaternion();
    const Matrix4d lu = left_matrix(u);
    const Matrix4d s_ux = lu * bingham::second_moment_matrix(s) * lu.transpose();
    const Matrix4d b = bingham::second_moment_matrix(w);
    Matrix4d s_ref = Matrix4d::Zero();
    for (int a = 0; a < 4; ++a)
        for (int bb = 0; bb < 4; ++bb) {
            Vector4d ea = Vector4d::Zero(), eb = Vector4d::Zero();
            ea(a) = 1;
            eb(bb) = 1;
            s_ref += b(a, bb) * left_matrix(quat(ea)) * s_ux * left_matrix(quat(eb)).transpose();
        }
    bingham::Filter g = f.clone();
    g.predict_world(u, w);
    const double d_moment = (Matrix4d(bingham::second_moment_matrix(g.state())) - s_ref).cwiseAbs().maxCoeff();
    if (d_moment >= 1e-10) std::fprintf(stderr, "    predict_world second moment off by %.3g\n", d_moment);
    CHECK(d_moment < 1e-10);
    // without a control: the identity
    bingham::Filter g0 = f.clone(), g1 = f.clone();
    g0.predict_world(w);
    g1.predict_world(Quaterniond::Identity(), w);
    CHECK(same(g0.state(), g1.state()));

    // update: the product with the likelihood whose directions are conj(m_i) * y (Eigen)
    const Quaterniond y = random_quaternion();
    Matrix4d ml;
    const Matrix4d mv = v.matrix();
    for (int j = 0; j < 4; ++j) {
        const Quaterniond p = quat(mv.col(j)).conjugate() * y;
        ml.col(j) = Vector4d(p.w(), p.x(), p.y(), p.z());
    }
    const bingham::Distribution lik(ml, v.concentrations());
    const bingham::Distribution want = bingham::multiply(s, lik);
    bingham::Filter h = f.clone();
    h.update_world(y, v);
    const double d_update = (precision(h.state()) - precision(want)).cwiseAbs().maxCoeff() / 500.0;
    CHECK(d_update < 1e-12);
    bingham_filter_free(c);
}

static void test_spin_filter() {
    static_assert(std::is_same<decltype(std::declval<const bingham::SpinFilter &>().spin_mode()), Quaterniond>::value &&
                      std::is_same<decltype(std::declval<const bingham::SpinFilter &>().orientation_mode()),
                                   Quaterniond>::value,
                  "SpinFilter's estimates are Eigen::Quaterniond");
    const bingham::Distribution bx(random_orthogonal(), Vector4d(-60, -25, -8, 0));
    const bingham::Distribution bv(random_orthogonal(), Vector4d(-40, -30, -5, 0));
    const bingham::Distribution w(random_orthogonal(), Vector4d(-400, -300, -100, 0));
    const bingham::Distribution o(random_orthogonal(), Vector4d(-40, -40, -10, 0));
    bingham::SpinFilter f(bx, bv), wrong(bx, bv);
    // the predictive density is the world-frame one of the composed prior
    bingham::Filter first(bingham::compose(bv, bx));
    for (int k = 0; k < 5; ++k) {
        const Quaterniond y = random_quaternion();
        const double a = f.log_likelihood(y, o), b = first.log_likelihood_world(y, o);
        CHECK(std::abs(a - b) < 1e-9 * (1 + std::abs(b)));
    }
    bingham_spin_filter *c = nullptr;
    CHECK_OK(bingham_spin_filter_new(bx.M.data(), bx.z.data(), bv.M.data(), bv.z.data(), &c));
    for (int k = 0; k < 10; ++k) {
        const Quaterniond u = random_quaternion(), y = random_quaternion();
        const double uc[4] = {u.w(), u.x(), u.y(), u.z()}, yc[4] = {y.w(), y.x(), y.y(), y.z()};
        f.step(u, w, y, o);
        CHECK_OK(bingham_spin_filter_step(c, uc, w.M.data(), w.z.data(), yc, o.M.data(), o.z.data()));
        CHECK_OK(bingham_spin_filter_step(wrong.get(), u.coeffs().data(), w.M.data(), w.z.data(), y.coeffs().data(),
                                          o.M.data(), o.z.data()));
    }
    double mx[16], zx[4], mv[16], zv[4], qx[4], qv[4];
    CHECK_OK(bingham_spin_filter_get_state(c, mx, zx, mv, zv));
    CHECK_OK(bingham_spin_filter_orientation_mode(c, qx));
    CHECK_OK(bingham_spin_filter_spin_mode(c, qv));
    const bingham::Distribution sx = f.orientation(), sv = f.spin();
    CHECK(std::memcmp(sx.M.data(), mx, sizeof mx) == 0 && std::memcmp(sv.z.data(), zv, sizeof zv) == 0);
    CHECK(!same(sv, wrong.spin()));
    const Quaterniond ex = f.orientation_mode(), ev = f.spin_mode();
    CHECK(ex.w() == qx[0] && ex.x() == qx[1] && ex.y() == qx[2] && ex.z() == qx[3]);
    CHECK(ev.w() == qv[0] && ev.x() == qv[1] && ev.y() == qv[2] && ev.z() == qv[3]);
    bingham_spin_filter_free(c);

    // a noiseless constant spin, uniform orientation prior, broad spin prior at the identity
    const Matrix4d eye = Matrix4d::Identity();
    bingham::SpinFilter s(bingham::Distribution(eye, Vector4d::Zero()), bingham::Distribution(eye, Vector4d(0, -3, -3, -3)));
    const bingham::Distribution sharp(eye, Vector4d(0, -400, -400, -400));
    const Quaterniond spin(Eigen::AngleAxisd(1.2, Vector3d(0.3, -1.0, 0.4).normalized()));  // ~69 deg per step
    Quaterniond x = random_quaternion();
    for (int k = 0; k < 300; ++k) {
        s.step(sharp, x, sharp);
        if (k < 299) x = spin * x;
    }
    const double err = s.spin_mode().angularDistance(spin), x_err = s.orientation_mode().angularDistance(x);
    if (err >= 1e-6 || x_err >= 1e-6) std::fprintf(stderr, "    spin error %.3g rad, orientation %.3g rad\n", err, x_err);
    CHECK(err < 1e-6 && x_err < 1e-6);
    const bingham::SpinSpread spread = s.angular_spread();
    // the spin is composed with the process noise last: its spread lies between the noise's and twice that
    const double noise_spread = bingham::angular_spread(sharp)[3];
    CHECK(spread.spin[3] > noise_spread && spread.spin[3] < 2 * noise_spread);
}

// bingham::smooth on Eigen matrices (column-major n x 3 in, n x 4 out, the spreads): equal to the
// std::vector overload and the C call; a wrong shape throws.
static void test_smooth() {
    const int n = 200;
    Eigen::MatrixXd gm(n, 3), am(n, 3), mm(n, 3);
    std::vector<double> gv, av, mv;
    for (int k = 0; k < n; ++k) {
        const double yaw = 0.003 * k;
        gm.row(k) << 0.001, -0.002, 0.3;
        am.row(k) << 0.0, 0.0, 9.81;
        mm.row(k) << 20.0 * std::sin(yaw), 20.0 * std::cos(yaw), -40.0;
        for (int c = 0; c < 3; ++c) gv.push_back(gm(k, c)), av.push_back(am(k, c)), mv.push_back(mm(k, c));
    }
    const bingham::AhrsParams p = bingham::ahrs_default_params(0.01);
    Eigen::VectorXd spread;
    const auto qe = bingham::smooth(p, gm, am, mm, &spread);
    const std::vector<double> qv = bingham::smooth(p, gv, av, mv);
    std::vector<double> qc(4 * n), sc(n);
    CHECK_OK(bingham_ahrs_smooth(&p, n, gv.data(), av.data(), mv.data(), qc.data(), sc.data()));
    CHECK(qe.rows() == n && qe.cols() == 4 && spread.size() == n);
    bool same = true;
    for (int k = 0; k < n; ++k) {
        for (int c = 0; c < 4; ++c) same = same && qe(k, c) == qv[4 * k + c] && qe(k, c) == qc[4 * k + c];
        same = same && spread(k) == sc[k];
    }
    CHECK(same);
    bool threw = false;
    try {
        (void)bingham::smooth(p, gm, Eigen::MatrixXd(n - 1, 3), mm);
    } catch (const bingham::Error &e) {
        threw = e.status() == BINGHAM_ERR_INVALID_DIMENSION;
    }
    CHECK(threw);
}

int main() {
    try {
        test_quaternions();
        test_storage_order();
        test_vectors();
        test_ahrs();
        test_world_steps();
        test_spin_filter();
        test_smooth();
    } catch (const std::exception &e) {
        std::fprintf(stderr, "unexpected exception: %s\n", e.what());
        return 1;
    }
    return check_summary(__cplusplus >= 202002L ? "wrapper_eigen (C++20)" : "wrapper_eigen (C++17)");
}
