// standards: c++17 c++20
//
// The C++ wrapper (include/bingham.hpp) without Eigen, against the C API it wraps:
//
// - every wrapped free function gives bit for bit what the C call gives for the same input;
// - errors throw bingham::Error whose status() is the C status and whose what() is the message
//   bingham_last_error_message() reports for the same C call; sizes the C API cannot check
//   (Distribution, vectors) throw BINGHAM_ERR_INVALID_DIMENSION before the library is called;
//   a failing call leaves its target (a Filter, an Ahrs, the variable assigned to) unchanged;
// - Filter (also its world-frame steps), SpinFilter and Ahrs: the same steps as a C handle give
//   bit-identical states; a moved-from handle
//   is empty (operator bool false, methods throw BINGHAM_ERR_NULL_ARGUMENT), safe to destroy and
//   to assign to; move assignment releases the old handle (LeakSanitizer, `make sanitize`,
//   would report a leak, ASan a double free); clone() is independent of its original;
// - the world-frame update equals bingham::multiply() with the likelihood written out here
//   (directions conj(m_i) y), the world-frame prediction with a control equals
//   compose(noise, rotate_left(state, u)); SpinFilter on a noiseless constant spin converges to
//   it (spin mode within 1e-6 rad after 300 steps).
// - Filter::surprise (quaternion and complex) equals bingham_filter_surprise; update_gated's
//   Gated{accepted, surprise} equals bingham_filter_update_gated's outputs on a C handle in the
//   same state, and the states stay equal (a measurement in (x, y, z, w) order gated out, the
//   filter unchanged); NaN / negative max_surprise throw with the C call's status and message;
// - Ahrs::health() equals bingham_ahrs_health field by field (the missing times included); all
//   zero on a fresh AHRS.
// - Ahrs::update_dt, the timed Ahrs::update_batch(t, gyr, acc, mag) and
//   Ahrs::orientation_covariance(): bit for bit the C calls (update_dt, _update_batch_timed,
//   _orientation_covariance) on a handle fed the same, with jittered steps and NaN rows (gyroscope
//   gaps included); update_dt(sample_time) == update; uniform timestamps == the untimed batch;
//   a bad dt and a timestamp not after the previous one throw with the C call's status and
//   message ("sample 7"), the AHRS unchanged resp. in the C handle's state; a NaN gyroscope
//   sample accepted as by the C call (gyr_missing_time = sample_time), a gyroscope turning by
//   more than 1e6 rad refused; sizes checked before the library is called; moved-from throws.
// - bingham::NonlinearOptions{} holds the defaults of bingham_nonlinear_options_default.
//
// Built as C++17 and as C++20 with -Wall -Wextra -Werror -pedantic (tests/c_tests.rs) and under
// ASan + UBSan + LSan (scripts/sanitize.sh).
#include "bingham.hpp"

#include <cmath>
#include <stdexcept>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "check.h"

static_assert(!BINGHAM_HPP_EIGEN, "this test is the configuration without Eigen");
static_assert(!std::is_copy_constructible_v<bingham::Filter> && std::is_nothrow_move_constructible_v<bingham::Filter> &&
                  std::is_nothrow_move_assignable_v<bingham::Filter>,
              "Filter is move-only");
static_assert(!std::is_copy_constructible_v<bingham::Ahrs> && std::is_nothrow_move_constructible_v<bingham::Ahrs>,
              "Ahrs is move-only");
static_assert(!std::is_copy_constructible_v<bingham::SpinFilter> && !std::is_copy_assignable_v<bingham::SpinFilter> &&
                  std::is_nothrow_move_constructible_v<bingham::SpinFilter> &&
                  std::is_nothrow_move_assignable_v<bingham::SpinFilter>,
              "SpinFilter is move-only");
static_assert(std::is_same_v<decltype(std::declval<const bingham::SpinFilter &>().spin_mode()), bingham::Quaternion>,
              "without Eigen, the estimates are bingham::Quaternion");

static bool same(const std::vector<double> &a, const std::vector<double> &b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}
static bool same(const bingham::Distribution &a, const bingham::Distribution &b) {
    return a.d == b.d && same(a.M, b.M) && same(a.z, b.z);
}

// Runs `f`, expecting a bingham::Error with `status`; if `c_call` is given, it is the same call
// through the C API, whose status and message must equal the exception's.
template <class F, class C>
static void expect_error(F f, bingham_status status, C c_call, const char *what) {
    try {
        f();
        check_report(0, __FILE__, __LINE__, what);
        std::fprintf(stderr, "    no exception\n");
    } catch (const bingham::Error &e) {
        const std::string msg = e.what();
        check_report(e.status() == status, __FILE__, __LINE__, what);
        check_report(!msg.empty() && e.message() == msg, __FILE__, __LINE__, what);
        if constexpr (!std::is_same_v<C, std::nullptr_t>) {
            const bingham_status st = c_call();
            check_report(st == status, __FILE__, __LINE__, what);
            if (bingham::last_error_message() != msg)
                std::fprintf(stderr, "    C: \"%s\"\n    C++: \"%s\"\n", bingham::last_error_message().c_str(),
                             msg.c_str());
            check_report(bingham::last_error_message() == msg, __FILE__, __LINE__, what);
        }
    }
}
template <class F>
static void expect_error(F f, bingham_status status, const char *what) {
    expect_error(f, status, nullptr, what);
}

static const double PI = 3.14159265358979323846;

static void test_free_functions() {
    using bingham::Distribution;
    const double c = std::cos(0.4), s = std::sin(0.4);
    // a d = 4 distribution: a rotation of the identity in the (0, 3) and (1, 2) planes
    const Distribution a({c, 0, 0, -s, 0, c, -s, 0, 0, s, c, 0, s, 0, 0, c}, {-30, -12, -3, 0});
    const Distribution b({0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 0}, {-500, -200, -50, 0});
    const std::size_t d = 4;

    // normalization constant and derivatives
    {
        const std::vector<double> z = {-5, -2, -1, 0};
        double f, lf, df[4], dlf[4], h[16];
        CHECK_OK(bingham_normalization_constant(d, z.data(), &f, df));
        CHECK_OK(bingham_log_normalization_hessian(d, z.data(), &lf, dlf, h));
        CHECK(bingham::normalization_constant(z) == f);
        const auto g = bingham::normalization_constant_gradient(z);
        CHECK(g.value == f && same(g.gradient, std::vector<double>(df, df + 4)));
        CHECK(bingham::log_normalization_constant(z) == lf);
        const auto lg = bingham::log_normalization_constant_gradient(z);
        CHECK(lg.value == lf && same(lg.gradient, std::vector<double>(dlf, dlf + 4)));
        const auto hh = bingham::log_normalization_hessian(z);
        CHECK(same(hh.hessian, std::vector<double>(h, h + 16)) && same(hh.gradient, lg.gradient));
        CHECK_CLOSE(bingham::normalization_constant({0, 0, 0, 0}), 2 * PI * PI, 1e-14);
        double sp, dsp[4];
        CHECK_OK(bingham_log_normalization_constant_saddlepoint(d, z.data(), &sp, dsp));
        CHECK(bingham::log_normalization_constant_saddlepoint(z).value == sp);
        const std::vector<double> big = {800, 0, 0};
        expect_error([&] { (void)bingham::normalization_constant(big); }, BINGHAM_ERR_NUMERICAL,
                     [&] {
                         double v;
                         return bingham_normalization_constant(3, big.data(), &v, nullptr);
                     },
                     "normalization_constant overflow");
        expect_error([] { (void)bingham::log_normalization_constant({0.0}); }, BINGHAM_ERR_INVALID_DIMENSION,
                     "d = 1");
    }
    // moments, MLE
    std::vector<double> s_c(16), m_c(16), z_c(4);
    CHECK_OK(bingham_second_moment(d, a.M.data(), a.z.data(), s_c.data()));
    CHECK(same(bingham::second_moment(a), s_c));
    CHECK_OK(bingham_mle(d, s_c.data(), m_c.data(), z_c.data()));
    const Distribution fit = bingham::mle(4, s_c);
    CHECK(same(fit.M, m_c) && same(fit.z, z_c) && fit.d == 4);
    CHECK_CLOSE(fit.z[0], -30.0, 1e-8);
    // multiply, compose, rotate
    {
        std::vector<double> m(16), z(4);
        CHECK_OK(bingham_multiply(d, a.M.data(), a.z.data(), b.M.data(), b.z.data(), m.data(), z.data()));
        CHECK(same(bingham::multiply(a, b), Distribution(m, z)));
        CHECK_OK(bingham_compose(d, a.M.data(), a.z.data(), b.M.data(), b.z.data(), m.data(), z.data()));
        CHECK(same(bingham::compose(a, b), Distribution(m, z)));
        const std::vector<double> u = {0.5, 0.5, -0.5, 0.5};
        CHECK_OK(bingham_rotate_left(d, a.M.data(), a.z.data(), u.data(), m.data(), z.data()));
        CHECK(same(bingham::rotate_left(a, u), Distribution(m, z)));
        CHECK(same(bingham::rotate_left(a, bingham::Quaternion(0.5, 0.5, -0.5, 0.5)), Distribution(m, z)));
        CHECK_OK(bingham_rotate_right(d, a.M.data(), a.z.data(), u.data(), m.data(), z.data()));
        CHECK(same(bingham::rotate_right(a, u), Distribution(m, z)));
        CHECK(same(bingham::rotate_right(a, {0.5, 0.5, -0.5, 0.5}), Distribution(m, z)));
    }
    // mode, pdf, sample, spread, entropy, KL
    {
        std::vector<double> mo(4);
        CHECK_OK(bingham_mode(d, a.M.data(), a.z.data(), mo.data()));
        CHECK(same(bingham::mode(a), mo));
        const bingham::Quaternion q = bingham::mode_quaternion(a);
        CHECK(q.w == mo[0] && q.x == mo[1] && q.y == mo[2] && q.z == mo[3]);
        const std::vector<double> x = bingham::sample(a, 5, 42);
        std::vector<double> xc(20), p(5), lp(5);
        CHECK_OK(bingham_sample(d, a.M.data(), a.z.data(), 42, 5, xc.data()));
        CHECK(same(x, xc));
        CHECK_OK(bingham_pdf(d, a.M.data(), a.z.data(), 5, x.data(), p.data()));
        CHECK_OK(bingham_log_pdf(d, a.M.data(), a.z.data(), 5, x.data(), lp.data()));
        CHECK(same(bingham::pdf_points(a, x), p) && same(bingham::log_pdf_points(a, x), lp));
        CHECK(bingham::pdf(a, std::vector<double>(x.begin(), x.begin() + 4)) == p[0]);
        CHECK(bingham::log_pdf(a, bingham::Quaternion(x[4], x[5], x[6], x[7])) == lp[1]);
        std::vector<double> sp(4);
        CHECK_OK(bingham_angular_spread(d, a.M.data(), a.z.data(), sp.data()));
        CHECK(same(bingham::angular_spread(a), sp));
        double h, kl;
        CHECK_OK(bingham_entropy(d, a.M.data(), a.z.data(), &h));
        CHECK_OK(bingham_kl_divergence(d, a.M.data(), a.z.data(), b.M.data(), b.z.data(), &kl));
        CHECK(bingham::entropy(a) == h && bingham::kl_divergence(a, b) == kl);
        // a non-unit point: the C message names the row
        std::vector<double> bad = x;
        bad[9] += 0.5;
        std::vector<double> out(5, 7.0);
        expect_error([&] { out = bingham::pdf_points(a, bad); }, BINGHAM_ERR_INVALID_ARGUMENT,
                     [&] { return bingham_pdf(d, a.M.data(), a.z.data(), 5, bad.data(), p.data()); }, "pdf row 2");
        CHECK(same(out, std::vector<double>(5, 7.0)));
        expect_error([&] { (void)bingham::pdf(a, {1.0, 0.0}); }, BINGHAM_ERR_INVALID_DIMENSION, "pdf size");
        std::vector<double> wc(16), wzc(4);
        CHECK_OK(bingham_mle_samples(d, 5, x.data(), nullptr, wc.data(), wzc.data()));
        CHECK(same(bingham::mle_samples(4, x), Distribution(wc, wzc)));
    }
    // noise helpers, vector observation
    {
        std::vector<double> m(16), z(4);
        CHECK_OK(bingham_noise_from_angle_std(4, 0.05, m.data(), z.data()));
        CHECK(same(bingham::noise_from_angle_std(4, 0.05), Distribution(m, z)));
        CHECK(same(bingham::noise_from_angle_std_deg(4, 2.0), bingham::noise_from_angle_std(4, 2.0 * PI / 180.0)));
        CHECK(same(bingham::noise_from_angle_std_deg(2, 30.0), bingham::noise_from_angle_std(2, PI / 6.0)));
        const std::array<double, 3> body = {0.6, 0.0, 0.8}, ref = {0.0, 0.0, 1.0};
        CHECK_OK(bingham_vector_observation(body.data(), ref.data(), 40.0, m.data(), z.data()));
        CHECK(same(bingham::vector_observation(body, ref, 40.0), Distribution(m, z)));
        expect_error([] { (void)bingham::noise_from_angle_std_deg(4, -1.0); }, BINGHAM_ERR_INVALID_ARGUMENT,
                     [] {
                         double mm[16], zz[4];
                         return bingham_noise_from_angle_std(4, -PI / 180.0, mm, zz);
                     },
                     "negative sigma");
        expect_error([] { (void)bingham::noise_from_angle_std(3, 0.1); }, BINGHAM_ERR_INVALID_DIMENSION,
                     [] {
                         double mm[9], zz[3];
                         return bingham_noise_from_angle_std(3, 0.1, mm, zz);
                     },
                     "noise d = 3");
    }
    // errors: the C message, and the assigned variable is unchanged
    {
        const std::vector<double> nonsym = {1.0, 2.0, 0.0, 1.0};
        Distribution keep = a;
        expect_error([&] { keep = bingham::mle(2, nonsym); }, BINGHAM_ERR_INVALID_ARGUMENT,
                     [&] {
                         double mm[4], zz[2];
                         return bingham_mle(2, nonsym.data(), mm, zz);
                     },
                     "mle of a non-symmetric matrix");
        CHECK(same(keep, a));
        Distribution skew = b;
        skew.M[0] = 0.5;  // not orthogonal
        expect_error([&] { keep = bingham::multiply(a, skew); }, BINGHAM_ERR_INVALID_ARGUMENT,
                     [&] {
                         double mm[16], zz[4];
                         return bingham_multiply(d, a.M.data(), a.z.data(), skew.M.data(), skew.z.data(), mm, zz);
                     },
                     "multiply with a non-orthogonal M");
        CHECK(same(keep, a));
        expect_error([&] { keep = bingham::compose(a, bingham::noise_from_angle_std(2, 0.1)); },
                     BINGHAM_ERR_INVALID_DIMENSION, "compose d = 4 with d = 2");
        expect_error([] { Distribution bad({1, 0, 0, 1}, {0, 0, 0}); }, BINGHAM_ERR_INVALID_DIMENSION,
                     "Distribution with mismatched sizes");
        CHECK(same(keep, a));
        try {
            (void)bingham::mle(2, nonsym);
        } catch (const std::runtime_error &e) {  // catchable as std::runtime_error too
            CHECK(std::strstr(e.what(), "bingham_mle") != nullptr);
        }
    }
    CHECK(bingham::version() == bingham_version());
}

// Two filters, one through the wrapper and one through C, driven by the same steps.
static void test_filter() {
    using bingham::Distribution;
    using bingham::Filter;
    const Distribution init({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}, {-1, -1, -1, 0});
    const Distribution w = bingham::noise_from_angle_std_deg(4, 3.0);
    const Distribution v = bingham::noise_from_angle_std_deg(4, 5.0);
    Filter f(init);
    CHECK(static_cast<bool>(f) && f.dim() == 4);
    bingham_filter *c = nullptr;
    CHECK_OK(bingham_filter_new(4, init.M.data(), init.z.data(), &c));
    const double h = std::sqrt(0.5);
    const bingham::Quaternion u(std::cos(0.05), std::sin(0.05), 0, 0), meas(h, 0, h, 0);
    const double u_c[4] = {u.w, u.x, u.y, u.z}, meas_c[4] = {meas.w, meas.x, meas.y, meas.z};
    for (int k = 0; k < 5; ++k) {
        f.predict_rotation(u, w);
        f.update(meas, v);
        f.predict(w);
        CHECK_OK(bingham_filter_predict_rotation(c, u_c, w.M.data(), w.z.data()));
        CHECK_OK(bingham_filter_update(c, meas_c, v.M.data(), v.z.data()));
        CHECK_OK(bingham_filter_predict(c, w.M.data(), w.z.data()));
    }
    f.update_vector({0, 0, 1}, {0, 1, 0}, 50.0);
    CHECK_OK(bingham_filter_update_vector(c, std::array<double, 3>{0, 0, 1}.data(),
                                          std::array<double, 3>{0, 1, 0}.data(), 50.0));
    Distribution sc(std::vector<double>(16), std::vector<double>(4));
    CHECK_OK(bingham_filter_get_state(c, sc.M.data(), sc.z.data()));
    CHECK(same(f.state(), sc));
    std::vector<double> mo(4), sp(4);
    CHECK_OK(bingham_filter_mode(c, mo.data()));
    CHECK_OK(bingham_filter_angular_spread(c, sp.data()));
    CHECK(same(f.mode(), mo) && same(f.angular_spread(), sp) && f.uncertainty() == sp[3]);
    const bingham::Quaternion fq = f.mode_quaternion();
    CHECK(fq.w == mo[0] && fq.x == mo[1] && fq.y == mo[2] && fq.z == mo[3]);
    double ll_c, llv_c;
    CHECK_OK(bingham_filter_log_likelihood(c, meas_c, v.M.data(), v.z.data(), &ll_c));
    CHECK_OK(bingham_filter_log_likelihood_vector(c, std::array<double, 3>{1, 0, 0}.data(),
                                                  std::array<double, 3>{1, 0, 0}.data(), 5.0, &llv_c));
    CHECK(f.log_likelihood(meas, v) == ll_c && f.log_likelihood_vector({1, 0, 0}, {1, 0, 0}, 5.0) == llv_c);

    // surprise: the C call's value; update_gated: the C call's surprise and decision, the same
    // state afterwards (applied: as update(); gated out: unchanged)
    {
        double s_c = -1;
        CHECK_OK(bingham_filter_surprise(c, meas_c, v.M.data(), v.z.data(), &s_c));
        const double s_w = f.surprise(meas, v);
        CHECK(s_w == s_c && s_w >= 0);
        // the (x, y, z, w) order of the same quaternion: far from the state
        const bingham::Quaternion wrong(meas.x, meas.y, meas.z, meas.w);
        const double wrong_c[4] = {wrong.w, wrong.x, wrong.y, wrong.z};
        double sw_c = -1;
        CHECK_OK(bingham_filter_surprise(c, wrong_c, v.M.data(), v.z.data(), &sw_c));
        CHECK(f.surprise(wrong, v) == sw_c && sw_c > 16.27);
        const Distribution st0 = f.state();
        const Filter::Gated out = f.update_gated(wrong, v, 16.27);
        double gs_c = -1;
        std::int32_t acc_c = -1;
        CHECK_OK(bingham_filter_update_gated(c, wrong_c, v.M.data(), v.z.data(), 16.27, &gs_c, &acc_c));
        CHECK(!out.accepted && acc_c == 0 && out.surprise == gs_c && out.surprise == sw_c);
        CHECK(same(f.state(), st0));
        const Filter::Gated in = f.update_gated(meas, v, 16.27);
        CHECK_OK(bingham_filter_update_gated(c, meas_c, v.M.data(), v.z.data(), 16.27, &gs_c, &acc_c));
        CHECK(in.accepted == (s_c <= 16.27) && acc_c == (in.accepted ? 1 : 0) && in.surprise == gs_c &&
              in.surprise == s_c);
        // the measurement the filter has been fed: applied
        CHECK(in.accepted && s_c <= 16.27 && !same(f.state(), st0));
        Distribution sg(std::vector<double>(16), std::vector<double>(4));
        CHECK_OK(bingham_filter_get_state(c, sg.M.data(), sg.z.data()));
        CHECK(same(f.state(), sg));
        // errors: the C call's status and message, the filter unchanged
        const Distribution st1 = f.state();
        expect_error([&] { (void)f.update_gated(meas, v, std::nan("")); }, BINGHAM_ERR_INVALID_ARGUMENT,
                     [&] {
                         double ss;
                         std::int32_t aa;
                         return bingham_filter_update_gated(c, meas_c, v.M.data(), v.z.data(), std::nan(""), &ss, &aa);
                     },
                     "update_gated with a NaN max_surprise");
        expect_error([&] { (void)f.update_gated(meas, v, -1.0); }, BINGHAM_ERR_INVALID_ARGUMENT,
                     [&] {
                         double ss;
                         std::int32_t aa;
                         return bingham_filter_update_gated(c, meas_c, v.M.data(), v.z.data(), -1.0, &ss, &aa);
                     },
                     "update_gated with a negative max_surprise");
        expect_error([&] { (void)f.surprise(bingham::Quaternion(2, 0, 0, 0), v); }, BINGHAM_ERR_INVALID_ARGUMENT,
                     [&] {
                         const double bad[4] = {2, 0, 0, 0};
                         double ss;
                         return bingham_filter_surprise(c, bad, v.M.data(), v.z.data(), &ss);
                     },
                     "surprise of a non-unit quaternion");
        expect_error([&] { (void)f.surprise(std::complex<double>(1, 0), v); }, BINGHAM_ERR_INVALID_DIMENSION,
                     "complex surprise on a d = 4 filter");
        expect_error([&] { (void)f.update_gated(std::complex<double>(1, 0), v, 16.27); },
                     BINGHAM_ERR_INVALID_DIMENSION, "complex update_gated on a d = 4 filter");
        CHECK(same(f.state(), st1));
    }

    // errors leave the filter unchanged
    const Distribution before = f.state();
    expect_error([&] { f.update(bingham::Quaternion(2, 0, 0, 0), v); }, BINGHAM_ERR_INVALID_ARGUMENT,
                 [&] {
                     const double bad[4] = {2, 0, 0, 0};
                     return bingham_filter_update(c, bad, v.M.data(), v.z.data());
                 },
                 "update with a non-unit quaternion");
    expect_error([&] { f.update(std::complex<double>(1, 0), v); }, BINGHAM_ERR_INVALID_DIMENSION,
                 "complex measurement on a d = 4 filter");
    expect_error([&] { f.predict(bingham::noise_from_angle_std(2, 0.1)); }, BINGHAM_ERR_INVALID_DIMENSION,
                 "d = 2 noise on a d = 4 filter");
    expect_error([&] { f.update_vector({0, 0, std::nan("")}, {0, 0, 1}, 1.0); }, BINGHAM_ERR_INVALID_ARGUMENT,
                 [&] {
                     const double bb[3] = {0, 0, std::nan("")}, rr[3] = {0, 0, 1};
                     return bingham_filter_update_vector(c, bb, rr, 1.0);
                 },
                 "update_vector with NaN");
    expect_error([&] { (void)f.mode_complex(); }, BINGHAM_ERR_INVALID_DIMENSION, "mode_complex on d = 4");
    CHECK(same(f.state(), before));
    expect_error([] { Filter bad(Distribution({1, 0, 0, 0, 1, 0, 0, 0, 1}, {-1, -1, 0})); },
                 BINGHAM_ERR_INVALID_DIMENSION,
                 [] {
                     const double mm[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, zz[3] = {-1, -1, 0};
                     bingham_filter *x = nullptr;
                     return bingham_filter_new(3, mm, zz, &x);
                 },
                 "a d = 3 filter");

    // clone: independent of the original
    Filter g = f.clone();
    CHECK(same(g.state(), before));
    g.update(bingham::Quaternion(1, 0, 0, 0), v);
    CHECK(same(f.state(), before) && !same(g.state(), before));
    f.update(bingham::Quaternion(1, 0, 0, 0), v);
    CHECK(same(f.state(), g.state()));

    // move: the moved-from filter is empty, safe to use (throws), destroy and reassign
    Filter moved(std::move(f));
    CHECK(!f && f.dim() == 0 && f.get() == nullptr && static_cast<bool>(moved));
    CHECK(same(moved.state(), g.state()));
    expect_error([&] { (void)f.mode(); }, BINGHAM_ERR_NULL_ARGUMENT, "mode of a moved-from filter");
    expect_error([&] { f.predict(w); }, BINGHAM_ERR_NULL_ARGUMENT, "predict on a moved-from filter");
    expect_error([&] { (void)f.clone(); }, BINGHAM_ERR_NULL_ARGUMENT, "clone of a moved-from filter");
    f = std::move(g);  // assign into the moved-from one
    CHECK(static_cast<bool>(f) && !g && same(f.state(), moved.state()));
    moved = std::move(f);  // releases moved's old handle (LSan would see a leak otherwise)
    CHECK(!f && static_cast<bool>(moved));
    Filter &alias = moved;
    moved = std::move(alias);  // self-move-assignment keeps the handle
    CHECK(static_cast<bool>(moved) && moved.dim() == 4);

    // d = 2: complex numbers
    Filter axis(Distribution({1, 0, 0, 1}, {-1, 0}));
    const Distribution w2 = bingham::noise_from_angle_std(2, 0.1);
    axis.predict_rotation(std::polar(1.0, 0.3), w2);
    axis.update(std::polar(1.0, 0.35), w2);
    const std::complex<double> m2 = axis.mode_complex();
    const std::vector<double> m2v = axis.mode();
    CHECK(m2.real() == m2v[0] && m2.imag() == m2v[1]);
    expect_error([&] { axis.update(bingham::Quaternion(), w2); }, BINGHAM_ERR_INVALID_DIMENSION,
                 "quaternion on a d = 2 filter");
    // d = 2: surprise and update_gated with complex numbers against the C calls on a clone
    {
        bingham_filter *c2 = nullptr;
        CHECK_OK(bingham_filter_clone(axis.get(), &c2));
        const std::complex<double> near = std::polar(1.0, 0.33), far = std::polar(1.0, 1.3);
        const double near_c[2] = {near.real(), near.imag()}, far_c[2] = {far.real(), far.imag()};
        double s_near = -1, s_far = -1, gs = -1;
        std::int32_t acc = -1;
        CHECK_OK(bingham_filter_surprise(c2, near_c, w2.M.data(), w2.z.data(), &s_near));
        CHECK_OK(bingham_filter_surprise(c2, far_c, w2.M.data(), w2.z.data(), &s_far));
        CHECK(axis.surprise(near, w2) == s_near && axis.surprise(far, w2) == s_far && s_near < 10.83 && s_far > 10.83);
        const Distribution st = axis.state();
        const Filter::Gated out = axis.update_gated(far, w2, 10.83);
        CHECK_OK(bingham_filter_update_gated(c2, far_c, w2.M.data(), w2.z.data(), 10.83, &gs, &acc));
        CHECK(!out.accepted && acc == 0 && out.surprise == gs && gs == s_far && same(axis.state(), st));
        const Filter::Gated in = axis.update_gated(near, w2, 10.83);
        CHECK_OK(bingham_filter_update_gated(c2, near_c, w2.M.data(), w2.z.data(), 10.83, &gs, &acc));
        CHECK(in.accepted && acc == 1 && in.surprise == gs && gs == s_near && !same(axis.state(), st));
        Distribution s2(std::vector<double>(4), std::vector<double>(2));
        CHECK_OK(bingham_filter_get_state(c2, s2.M.data(), s2.z.data()));
        CHECK(same(axis.state(), s2));
        expect_error([&] { (void)axis.surprise(bingham::Quaternion(), w2); }, BINGHAM_ERR_INVALID_DIMENSION,
                     "quaternion surprise on a d = 2 filter");
        bingham_filter_free(c2);
    }
    bingham_filter_free(c);
}

// The nonlinear steps with C++ callables: bit-identical to the C functions with C callbacks; an
// exception thrown by the callable is rethrown with the filter unchanged; a non-finite value
// throws Error(BINGHAM_ERR_CALLBACK), filter unchanged.
static int c_turn(const double *x, double *out, void *) {
    const double c = std::cos(0.05), s = std::sin(0.05);
    out[0] = x[0] * c - x[3] * s;
    out[1] = x[1] * c + x[2] * s;
    out[2] = x[2] * c - x[1] * s;
    out[3] = x[3] * c + x[0] * s;
    return 0;
}

static double quartic(const double *x) {
    const double e = 1.0 - x[1] * x[1];
    return -20.0 * (1.0 - e) * (1.0 - e) - 3.0 * x[2] * x[2];
}

static int c_quartic(const double *x, double *log_l, void *) {
    *log_l = quartic(x);
    return 0;
}

static void test_filter_nonlinear() {
    using bingham::Distribution;
    const Distribution init({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}, {-30, -20, -10, 0});
    const Distribution w = bingham::noise_from_angle_std_deg(4, 3.0);
    bingham::Filter f(init);
    bingham_filter *c = nullptr;
    CHECK_OK(bingham_filter_new(4, init.M.data(), init.z.data(), &c));
    int calls = 0;
    for (int k = 0; k < 3; ++k) {
        f.predict_nonlinear(
            [&](const double *x, double *out) {
                ++calls;
                c_turn(x, out, nullptr);
            },
            w);
        f.update_nonlinear([](const double *x) { return quartic(x); });
        CHECK_OK(bingham_filter_predict_nonlinear(c, c_turn, nullptr, w.M.data(), w.z.data()));
        CHECK_OK(bingham_filter_update_nonlinear(c, c_quartic, nullptr));
    }
    CHECK(calls == 3 * 19);
    Distribution sc(std::vector<double>(16), std::vector<double>(4));
    CHECK_OK(bingham_filter_get_state(c, sc.M.data(), sc.z.data()));
    CHECK(same(f.state(), sc));

    const Distribution before = f.state();
    bool rethrown = false;
    try {
        f.update_nonlinear([](const double *) -> double { throw std::runtime_error("sensor model failed"); });
    } catch (const std::runtime_error &e) {
        rethrown = std::strcmp(e.what(), "sensor model failed") == 0;
    }
    CHECK(rethrown && same(f.state(), before));
    rethrown = false;
    try {
        f.predict_nonlinear([](const double *, double *) { throw std::runtime_error("dynamics failed"); }, w);
    } catch (const std::runtime_error &e) {
        rethrown = std::strcmp(e.what(), "dynamics failed") == 0;
    }
    CHECK(rethrown && same(f.state(), before));
    bool callback_error = false;
    try {
        f.update_nonlinear([](const double *) { return std::nan(""); });
    } catch (const bingham::Error &e) {
        callback_error = e.status() == BINGHAM_ERR_CALLBACK;
    }
    CHECK(callback_error && same(f.state(), before));

    // The options forms: the report, and a budget too small refused with the filter unchanged.
    bingham::NonlinearOptions o;
    {
        // the wrapper's defaults (member initializers) are the library's
        bingham_nonlinear_options dc;
        std::memset(&dc, 0xA5, sizeof dc);
        CHECK_OK(bingham_nonlinear_options_default(&dc));
        const bingham_nonlinear_options oc = o.c();
        CHECK(oc.tolerance == dc.tolerance && oc.mode_tolerance == dc.mode_tolerance && oc.max_calls == dc.max_calls);
    }
    int n = 0;
    const bingham::NonlinearReport rp = f.predict_nonlinear(
        [&](const double *x, double *out) {
            ++n;
            c_turn(x, out, nullptr);
        },
        w, o);
    CHECK(rp.method == BINGHAM_NONLINEAR_DETERMINISTIC && rp.calls == (std::size_t)n && n == 19);
    n = 0;
    const bingham::NonlinearReport ru = f.update_nonlinear(
        [&](const double *x) {
            ++n;
            return quartic(x);
        },
        o);
    CHECK(ru.method == BINGHAM_NONLINEAR_SAMPLED && ru.calls == (std::size_t)n);
    CHECK(ru.error_estimate <= BINGHAM_NONLINEAR_UPDATE_TOLERANCE && ru.samples >= 128);
    const Distribution kept = f.state();
    o.max_calls = 30;
    bool refused = false;
    try {
        f.update_nonlinear([](const double *x) { return quartic(x); }, o);
    } catch (const bingham::Error &e) {
        refused = e.status() == BINGHAM_ERR_NOT_CONVERGED && std::strstr(e.what(), "budget") != nullptr;
    }
    CHECK(refused && same(f.state(), kept));
    bingham_filter_free(c);
}

// Hamilton product q r, scalar first ("rotate by r, then by q").
static bingham::Quaternion qmul(const bingham::Quaternion &q, const bingham::Quaternion &r) {
    return {q.w * r.w - q.x * r.x - q.y * r.y - q.z * r.z, q.w * r.x + q.x * r.w + q.y * r.z - q.z * r.y,
            q.w * r.y - q.x * r.z + q.y * r.w + q.z * r.x, q.w * r.z + q.x * r.y - q.y * r.x + q.z * r.w};
}
static bingham::Quaternion qconj(const bingham::Quaternion &q) { return {q.w, -q.x, -q.y, -q.z}; }
// The rotation by `angle` about the unit `axis`.
static bingham::Quaternion axis_angle(double ax, double ay, double az, double angle) {
    const double n = std::sqrt(ax * ax + ay * ay + az * az), s = std::sin(angle / 2) / n;
    return {std::cos(angle / 2), s * ax, s * ay, s * az};
}
// The rotation angle between two orientations (q and -q the same).
static double angle_between(const bingham::Quaternion &a, const bingham::Quaternion &b) {
    const double c = std::fabs(a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z);
    return 2 * std::acos(c > 1 ? 1 : c);
}
// max |P_a - P_b| / max(1, max|z|), P = M diag(z) M^T: two Bingham densities' exponents.
static double precision_difference(const bingham::Distribution &a, const bingham::Distribution &b) {
    double diff = 0, scale = 1;
    for (std::size_t i = 0; i < a.d; ++i) {
        scale = std::fmax(scale, std::fabs(a.z[i]));
        for (std::size_t j = 0; j < a.d; ++j) {
            double pa = 0, pb = 0;
            for (std::size_t k = 0; k < a.d; ++k) {
                pa += a.m(i, k) * a.z[k] * a.m(j, k);
                pb += b.m(i, k) * b.z[k] * b.m(j, k);
            }
            diff = std::fmax(diff, std::fabs(pa - pb));
        }
    }
    return diff / scale;
}
// The likelihood of y = v o x, v ~ noise, as a Bingham density of x: directions conj(m_i) y.
static bingham::Distribution world_likelihood(const bingham::Quaternion &y, const bingham::Distribution &noise) {
    bingham::Distribution l = noise;
    for (std::size_t j = 0; j < 4; ++j) {
        const bingham::Quaternion c = qmul(qconj({noise.m(0, j), noise.m(1, j), noise.m(2, j), noise.m(3, j)}), y);
        const double col[4] = {c.w, c.x, c.y, c.z};
        for (std::size_t i = 0; i < 4; ++i) l.M[i * 4 + j] = col[i];
    }
    return l;
}

// Filter's world-frame steps: bit for bit the C calls; against multiply / compose.
static void test_filter_world() {
    using bingham::Distribution;
    const double c = std::cos(0.3), s = std::sin(0.3);
    const Distribution init({c, 0, 0, -s, 0, c, -s, 0, 0, s, c, 0, s, 0, 0, c}, {-60, -25, -8, 0});
    // anisotropic noises (the paper's kind), modes at the identity
    const Distribution w({0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 0}, {-400, -200, -50, 0});
    const Distribution v({0, 0, 0, 1, 0, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0}, {-40, -40, -10, 0});
    bingham::Filter f(init);
    bingham_filter *h = nullptr;
    CHECK_OK(bingham_filter_new(4, init.M.data(), init.z.data(), &h));
    const bingham::Quaternion u = axis_angle(1, -2, 0.5, 0.7), y = axis_angle(0.3, 1, -1, 1.1);
    const double uc[4] = {u.w, u.x, u.y, u.z}, yc[4] = {y.w, y.x, y.y, y.z};
    for (int k = 0; k < 4; ++k) {
        if (k % 2) {
            f.predict_world(u, w);
            CHECK_OK(bingham_filter_predict_world(h, uc, w.M.data(), w.z.data()));
        } else {
            f.predict_world(w);
            CHECK_OK(bingham_filter_predict_world(h, nullptr, w.M.data(), w.z.data()));
        }
        double ll;
        CHECK_OK(bingham_filter_log_likelihood_world(h, yc, v.M.data(), v.z.data(), &ll));
        CHECK(f.log_likelihood_world(y, v) == ll);
        f.update_world(y, v);
        CHECK_OK(bingham_filter_update_world(h, yc, v.M.data(), v.z.data()));
    }
    Distribution sc(std::vector<double>(16), std::vector<double>(4));
    CHECK_OK(bingham_filter_get_state(h, sc.M.data(), sc.z.data()));
    CHECK(same(f.state(), sc));
    // independent: the update is the exact product with the likelihood written out here, the
    // prediction the moment-matched composition of the noise with the rotated state
    const Distribution prior = f.state();
    bingham::Filter g = f.clone();
    g.update_world(y, v);
    const double d_update = precision_difference(g.state(), bingham::multiply(prior, world_likelihood(y, v)));
    CHECK(d_update < 1e-12);
    g.predict_world(u, w);
    const Distribution posterior = bingham::multiply(prior, world_likelihood(y, v));
    const double d_predict =
        precision_difference(g.state(), bingham::compose(w, bingham::rotate_left(posterior, u)));
    if (d_predict >= 1e-9) std::fprintf(stderr, "    predict_world vs compose: %.3g\n", d_predict);
    CHECK(d_predict < 1e-9);
    // the world frame is not the body frame for an anisotropic noise
    bingham::Filter body = f.clone();
    body.update(y, v);
    CHECK(precision_difference(body.state(), g.state()) > 1e-3);
    // errors: the filter is unchanged, the message the C call's
    const Distribution before = f.state();
    expect_error([&] { f.update_world(bingham::Quaternion(1, 0.1, 0, 0), v); }, BINGHAM_ERR_INVALID_ARGUMENT,
                 [&] {
                     const double bad[4] = {1, 0.1, 0, 0};
                     return bingham_filter_update_world(h, bad, v.M.data(), v.z.data());
                 },
                 "update_world with a non-unit quaternion");
    expect_error([&] { f.predict_world(bingham::Quaternion(std::nan(""), 0, 0, 1), w); },
                 BINGHAM_ERR_INVALID_ARGUMENT,
                 [&] {
                     const double bad[4] = {std::nan(""), 0, 0, 1};
                     return bingham_filter_predict_world(h, bad, w.M.data(), w.z.data());
                 },
                 "predict_world with NaN");
    expect_error([&] { (void)f.log_likelihood_world(std::complex<double>(1, 0), v); },
                 BINGHAM_ERR_INVALID_DIMENSION, "complex y on a d = 4 filter");
    expect_error([&] { f.predict_world(bingham::noise_from_angle_std(2, 0.1)); }, BINGHAM_ERR_INVALID_DIMENSION,
                 "d = 2 noise on a d = 4 filter");
    CHECK(same(f.state(), before));
    bingham::Filter taken = std::move(g);
    expect_error([&] { g.predict_world(w); }, BINGHAM_ERR_NULL_ARGUMENT, "predict_world on a moved-from filter");
    // d = 2: complex numbers (the world frame is the body frame: multiplication commutes)
    bingham::Filter axis(Distribution({1, 0, 0, 1}, {-1, 0})), axis_body = axis.clone();
    const Distribution w2({0, 1, 1, 0}, {-50, 0}), v2({0, 1, 1, 0}, {-5, 0});
    axis.predict_world(std::polar(1.0, 0.3), w2);
    axis_body.predict_rotation(std::polar(1.0, 0.3), w2);
    axis.update_world(std::polar(1.0, 0.35), v2);
    axis_body.update(std::polar(1.0, 0.35), v2);
    CHECK(precision_difference(axis.state(), axis_body.state()) < 1e-12);
    CHECK_CLOSE(axis.log_likelihood_world(std::polar(1.0, 0.2), v2),
                axis_body.log_likelihood(std::polar(1.0, 0.2), v2), 1e-12);
    bingham_filter_free(h);
}

static void get_spin_state(const bingham_spin_filter *h, bingham::Distribution &x, bingham::Distribution &v) {
    x = bingham::Distribution(std::vector<double>(16), std::vector<double>(4));
    v = x;
    CHECK_OK(bingham_spin_filter_get_state(h, x.M.data(), x.z.data(), v.M.data(), v.z.data()));
}

// SpinFilter: every overload bit for bit the C calls; convergence; errors, clone, move.
static void test_spin_filter() {
    using bingham::Distribution;
    using bingham::Quaternion;
    const std::vector<double> eye = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    const Distribution uniform(eye, {0, 0, 0, 0});
    const Distribution spin_prior(eye, {0, -3, -3, -3});  // mode (1, 0, 0, 0): no spin, broad
    const Distribution w(eye, {0, -400, -300, -200});      // anisotropic process noise on the spin
    const Distribution o({0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 0}, {-40, -40, -10, 0});
    bingham::SpinFilter f(uniform, spin_prior);
    CHECK(static_cast<bool>(f));
    bingham_spin_filter *h = nullptr;
    CHECK_OK(bingham_spin_filter_new(uniform.M.data(), uniform.z.data(), spin_prior.M.data(), spin_prior.z.data(),
                                     &h));
    const Quaternion spin = axis_angle(0.2, -0.4, 1.0, 1.0);  // ~57 degrees per step
    const Quaternion u = axis_angle(1, 0, 0, 0.01);
    Quaternion x = axis_angle(1, 1, 0, 0.4);
    bool all_same = true, all_ll = true;
    for (int k = 0; k < 24; ++k) {
        const double xc[4] = {x.w, x.x, x.y, x.z}, uc[4] = {u.w, u.x, u.y, u.z};
        const bool observed = k % 5 != 4, control = k % 3 == 2;
        if (observed) {
            double ll;
            CHECK_OK(bingham_spin_filter_log_likelihood(h, xc, o.M.data(), o.z.data(), &ll));
            all_ll = all_ll && f.log_likelihood(x, o) == ll;
        }
        if (observed && control) f.step(u, w, x, o);
        if (observed && !control) f.step(w, x, o);
        if (!observed && control) f.step(u, w);
        if (!observed && !control) f.step(w);
        CHECK_OK(bingham_spin_filter_step(h, control ? uc : nullptr, w.M.data(), w.z.data(),
                                          observed ? xc : nullptr, observed ? o.M.data() : nullptr,
                                          observed ? o.z.data() : nullptr));
        Distribution sx, sv;
        get_spin_state(h, sx, sv);
        const auto st = f.state();
        all_same = all_same && same(st.first, sx) && same(st.second, sv) && same(f.orientation(), sx) &&
                   same(f.spin(), sv);
        x = qmul(spin, x);
    }
    CHECK(all_same && all_ll);
    double qx[4], qv[4], sx[4], sv[4];
    CHECK_OK(bingham_spin_filter_orientation_mode(h, qx));
    CHECK_OK(bingham_spin_filter_spin_mode(h, qv));
    CHECK_OK(bingham_spin_filter_angular_spread(h, sx, sv));
    const Quaternion mx = f.orientation_mode(), mv = f.spin_mode();
    CHECK(mx.w == qx[0] && mx.x == qx[1] && mx.y == qx[2] && mx.z == qx[3]);
    CHECK(mv.w == qv[0] && mv.x == qv[1] && mv.y == qv[2] && mv.z == qv[3]);
    const bingham::SpinSpread spread = f.angular_spread();
    CHECK(std::memcmp(spread.orientation.data(), sx, sizeof sx) == 0 &&
          std::memcmp(spread.spin.data(), sv, sizeof sv) == 0);
    CHECK(spread.spin[3] > 0 && spread.orientation[3] > 0);

    // errors: the C call's status and message; the filter unchanged
    const auto before = f.state();
    expect_error([&] { f.step(w, Quaternion(1, 0.1, 0, 0), o); }, BINGHAM_ERR_INVALID_ARGUMENT,
                 [&] {
                     const double bad[4] = {1, 0.1, 0, 0};
                     return bingham_spin_filter_step(h, nullptr, w.M.data(), w.z.data(), bad, o.M.data(),
                                                     o.z.data());
                 },
                 "spin step with a non-unit observation");
    expect_error([&] { f.step(Quaternion(std::nan(""), 0, 0, 1), w); }, BINGHAM_ERR_INVALID_ARGUMENT,
                 [&] {
                     const double bad[4] = {std::nan(""), 0, 0, 1};
                     return bingham_spin_filter_step(h, bad, w.M.data(), w.z.data(), nullptr, nullptr, nullptr);
                 },
                 "spin step with a NaN control");
    Distribution skew = w;
    skew.M[1] = 0.5;
    expect_error([&] { f.step(skew); }, BINGHAM_ERR_INVALID_ARGUMENT,
                 [&] {
                     return bingham_spin_filter_step(h, nullptr, skew.M.data(), skew.z.data(), nullptr, nullptr,
                                                     nullptr);
                 },
                 "spin step with a non-orthogonal noise");
    expect_error([&] { (void)f.log_likelihood(Quaternion(2, 0, 0, 0), o); }, BINGHAM_ERR_INVALID_ARGUMENT,
                 [&] {
                     const double bad[4] = {2, 0, 0, 0};
                     double ll;
                     return bingham_spin_filter_log_likelihood(h, bad, o.M.data(), o.z.data(), &ll);
                 },
                 "spin log_likelihood with a non-unit observation");
    expect_error([&] { f.step(bingham::noise_from_angle_std(2, 0.1)); }, BINGHAM_ERR_INVALID_DIMENSION,
                 "a d = 2 noise");
    expect_error([&] { f.set_state(uniform, Distribution({1, 0, 0, 1}, {-1, 0})); }, BINGHAM_ERR_INVALID_DIMENSION,
                 "set_state with a d = 2 spin");
    expect_error([&] { bingham::SpinFilter bad(uniform, skew); }, BINGHAM_ERR_INVALID_ARGUMENT,
                 [&] {
                     bingham_spin_filter *x2 = nullptr;
                     return bingham_spin_filter_new(uniform.M.data(), uniform.z.data(), skew.M.data(), skew.z.data(),
                                                    &x2);
                 },
                 "a non-orthogonal spin prior");
    CHECK(same(f.state().first, before.first) && same(f.state().second, before.second));

    // clone: independent; set_state
    bingham::SpinFilter g = f.clone();
    g.step(w);
    CHECK(same(f.state().second, before.second) && !same(g.state().first, before.first));
    g.set_state(before.first, before.second);
    CHECK(same(g.state().first, before.first) && same(g.state().second, before.second));
    // move: the moved-from filter is empty, safe to use (throws), destroy and reassign
    bingham::SpinFilter moved(std::move(f));
    CHECK(!f && f.get() == nullptr && static_cast<bool>(moved));
    expect_error([&] { f.step(w); }, BINGHAM_ERR_NULL_ARGUMENT, "step on a moved-from spin filter");
    expect_error([&] { (void)f.spin_mode(); }, BINGHAM_ERR_NULL_ARGUMENT, "spin_mode of a moved-from spin filter");
    expect_error([&] { (void)f.clone(); }, BINGHAM_ERR_NULL_ARGUMENT, "clone of a moved-from spin filter");
    f = std::move(g);
    CHECK(static_cast<bool>(f) && !g);
    moved = std::move(f);  // releases moved's old handle (LSan would see a leak otherwise)
    CHECK(!f && static_cast<bool>(moved));
    bingham_spin_filter_free(h);

    // a noiseless constant spin (uniform orientation prior, broad spin prior): the spin mode
    // converges to it, and the orientation to the truth
    bingham::SpinFilter c(uniform, spin_prior);
    const Distribution sharp_w(eye, {0, -400, -400, -400}), sharp_o(eye, {0, -400, -400, -400});
    x = axis_angle(-0.3, 0.8, 0.1, 2.0);
    double err20 = 0, err = 0, x_err = 0;
    for (int k = 0; k < 300; ++k) {
        c.step(sharp_w, x, sharp_o);
        err = angle_between(c.spin_mode(), spin);
        x_err = angle_between(c.orientation_mode(), x);
        if (k == 19) err20 = err;
        x = qmul(spin, x);
    }
    if (err >= 1e-6 || x_err >= 1e-6)
        std::fprintf(stderr, "    spin error %.3g rad (after 20 steps %.3g), orientation %.3g rad\n", err, err20,
                     x_err);
    CHECK(err < 1e-6 && x_err < 1e-6 && err20 < 0.2);
}

static bool same_health(const bingham_ahrs_health_report &a, const bingham_ahrs_health_report &b) {
    return a.score == b.score && a.gravity_score == b.gravity_score && a.tilt_score == b.tilt_score &&
           a.heading_score == b.heading_score && a.tilt_innovation == b.tilt_innovation &&
           a.heading_innovation == b.heading_innovation && a.mag_rejected == b.mag_rejected && a.mag_dip == b.mag_dip &&
           a.has_mag_reference == b.has_mag_reference && a.gyr_missing_time == b.gyr_missing_time &&
           a.acc_missing_time == b.acc_missing_time && a.mag_missing_time == b.mag_missing_time;
}

// Everything the getters of a C handle show, for bit-for-bit comparisons.
struct CState {
    double q[4], m[16], z[4], sp[4], bias[3], bcov[9], ocov[9];
    bingham_ahrs_health_report h;
};
static CState c_state(const bingham_ahrs *c) {
    CState s{};
    CHECK_OK(bingham_ahrs_quaternion(c, s.q));
    CHECK_OK(bingham_ahrs_state(c, s.m, s.z));
    CHECK_OK(bingham_ahrs_angular_spread(c, s.sp));
    CHECK_OK(bingham_ahrs_gyro_bias(c, s.bias));
    CHECK_OK(bingham_ahrs_gyro_bias_covariance(c, s.bcov));
    CHECK_OK(bingham_ahrs_orientation_covariance(c, s.ocov));
    CHECK_OK(bingham_ahrs_health(c, &s.h));
    return s;
}
static bool same_c_state(const CState &a, const CState &b) {
    return std::memcmp(a.q, b.q, sizeof a.q) == 0 && std::memcmp(a.m, b.m, sizeof a.m) == 0 &&
           std::memcmp(a.z, b.z, sizeof a.z) == 0 && std::memcmp(a.sp, b.sp, sizeof a.sp) == 0 &&
           std::memcmp(a.bias, b.bias, sizeof a.bias) == 0 && std::memcmp(a.bcov, b.bcov, sizeof a.bcov) == 0 &&
           std::memcmp(a.ocov, b.ocov, sizeof a.ocov) == 0 && same_health(a.h, b.h);
}

// Sample k of a turning stream (rad/s, m/s^2, any unit) as three arrays.
static void ahrs_sample(int k, std::array<double, 3> &g, std::array<double, 3> &ac, std::array<double, 3> &mg) {
    g = {0.1, -0.05, 0.2 * std::sin(0.1 * k)};
    ac = {0.3, -0.2, 9.7};
    mg = {0.1, 20.0, -40.0};
}

// update_dt, the timed batch, the orientation covariance and NaN gyroscope samples: bit for bit
// the C calls on a handle fed the same; errors with the C call's status and message, the AHRS
// unchanged.
static void test_ahrs_timing() {
    const double dt = 0.01;
    const std::array<double, 3> nan3 = {std::nan(""), std::nan(""), std::nan("")};
    bingham::Ahrs a(dt), u(dt);
    bingham_ahrs_params p;
    CHECK_OK(bingham_ahrs_params_default(dt, &p));
    bingham_ahrs *c = nullptr;
    CHECK_OK(bingham_ahrs_new(&p, &c));
    // before the first sample: the identity covariance
    {
        const std::array<double, 9> oc = a.orientation_covariance();
        for (std::size_t i = 0; i < 9; ++i) CHECK(oc[i] == (i % 4 == 0 ? 1.0 : 0.0));
    }
    // update_dt with and without the magnetometer, jittered steps, NaN rows (a gyroscope gap
    // too); update_dt(sample_time) == update on a third AHRS
    bool same_all = true, same_update = true;
    for (int k = 0; k < 120; ++k) {
        std::array<double, 3> g, ac, mg;
        ahrs_sample(k, g, ac, mg);
        if (k % 11 == 4) g = nan3;
        if (k % 13 == 6) ac[1] = std::nan("");
        const double h = k % 3 == 0 ? dt : dt * (1.0 + 0.2 * std::sin(1.3 * k));
        if (k % 4 == 1) {
            a.update_dt(h, g, ac);
            CHECK_OK(bingham_ahrs_update_dt(c, h, g.data(), ac.data(), nullptr));
        } else {
            a.update_dt(h, g, ac, mg);
            CHECK_OK(bingham_ahrs_update_dt(c, h, g.data(), ac.data(), mg.data()));
        }
        same_all = same_all && same_c_state(c_state(a.get()), c_state(c));
        // update_dt(sample_time) and update: one AHRS each, the same samples
        bingham::Ahrs v = u.clone();
        u.update_dt(dt, g, ac, mg);
        v.update(g, ac, mg);
        same_update = same_update && same_c_state(c_state(u.get()), c_state(v.get()));
    }
    CHECK(same_all && same_update);
    // the orientation covariance: the C call's, bit for bit; symmetric, trace = uncertainty()^2
    {
        double oc[9];
        CHECK_OK(bingham_ahrs_orientation_covariance(c, oc));
        const std::array<double, 9> aw = a.orientation_covariance();
        CHECK(std::memcmp(aw.data(), oc, sizeof oc) == 0);
        CHECK(aw[1] == aw[3] && aw[2] == aw[6] && aw[5] == aw[7]);
        const double s2 = a.uncertainty() * a.uncertainty();
        CHECK_CLOSE(aw[0] + aw[4] + aw[8], s2, 1e-12);
    }
    // a bad dt throws with the C call's status and message, the AHRS unchanged
    for (const double bad : {0.0, -0.01, std::nan(""), HUGE_VAL, 1e-7, 10.5}) {
        const CState before = c_state(a.get());
        std::array<double, 3> g, ac, mg;
        ahrs_sample(200, g, ac, mg);
        expect_error([&] { a.update_dt(bad, g, ac, mg); }, BINGHAM_ERR_INVALID_ARGUMENT,
                     [&] { return bingham_ahrs_update_dt(c, bad, g.data(), ac.data(), mg.data()); }, "a bad dt");
        CHECK(bingham::last_error_message().find("dt") != std::string::npos);
        CHECK(same_c_state(before, c_state(a.get())) && same_c_state(before, c_state(c)));
    }
    // the timed batch: the C call's quaternions and final state, bit for bit; split == one call;
    // uniform timestamps == the untimed batch
    {
        const std::size_t n = 60;
        std::vector<double> t(n), gyr, acc, mag;
        double tk = 7.0;
        for (std::size_t k = 0; k < n; ++k) {
            tk += dt * (1.0 + 0.3 * std::sin(0.7 * static_cast<double>(k))) + (k % 17 == 16 ? 2 * dt : 0.0);
            t[k] = tk;
            std::array<double, 3> g, ac, mg;
            ahrs_sample(static_cast<int>(300 + k), g, ac, mg);
            if (k % 9 == 2) g = nan3;
            gyr.insert(gyr.end(), g.begin(), g.end());
            acc.insert(acc.end(), ac.begin(), ac.end());
            mag.insert(mag.end(), mg.begin(), mg.end());
        }
        bingham::Ahrs b = a.clone();
        const std::vector<double> qa = a.update_batch(t, gyr, acc, mag);
        std::vector<double> qc(4 * n);
        CHECK_OK(bingham_ahrs_update_batch_timed(c, n, t.data(), gyr.data(), acc.data(), mag.data(), qc.data(),
                                                 nullptr, nullptr));
        CHECK(same(qa, qc) && same_c_state(c_state(a.get()), c_state(c)));
        const std::size_t cut = 23;
        const auto part = [&](std::size_t from, std::size_t to) {
            return std::vector<double>(t.begin() + static_cast<std::ptrdiff_t>(from),
                                       t.begin() + static_cast<std::ptrdiff_t>(to));
        };
        const auto rows = [&](const std::vector<double> &v, std::size_t from, std::size_t to) {
            return std::vector<double>(v.begin() + static_cast<std::ptrdiff_t>(3 * from),
                                       v.begin() + static_cast<std::ptrdiff_t>(3 * to));
        };
        std::vector<double> qb = b.update_batch(part(0, cut), rows(gyr, 0, cut), rows(acc, 0, cut), rows(mag, 0, cut));
        const std::vector<double> qb2 =
            b.update_batch(part(cut, n), rows(gyr, cut, n), rows(acc, cut, n), rows(mag, cut, n));
        CHECK(qb.size() == 4 * cut && qb2.size() == 4 * (n - cut));
        qb.insert(qb.end(), qb2.begin(), qb2.end());
        CHECK(same(qb, qa) && same_c_state(c_state(b.get()), c_state(a.get())));
        bingham_ahrs *d = nullptr;
        CHECK_OK(bingham_ahrs_clone(c, &d));
        bingham::Ahrs e = a.clone();
        // uniform timestamps == untimed, bit for bit
        std::vector<double> tu(n);
        for (std::size_t k = 0; k < n; ++k) tu[k] = 1000.0 + dt * static_cast<double>(k);
        bingham::Ahrs f = e.clone(), g = e.clone();
        f.update({0, 0, 0}, {0, 0, 9.81});  // an untimed sample: the next timed batch starts with sample_time
        g.update({0, 0, 0}, {0, 0, 9.81});
        const std::vector<double> qf = f.update_batch(tu, gyr, acc, mag), qg = g.update_batch(gyr, acc, mag);
        CHECK(same(qf, qg) && same_c_state(c_state(f.get()), c_state(g.get())));
        // a timestamp not after the previous one: throws with the C call's status and message
        // ("sample k"), the samples before it processed
        std::vector<double> tb(n);
        for (std::size_t k = 0; k < n; ++k) tb[k] = t[n - 1] + dt * static_cast<double>(k + 1);  // after e's last
        tb[7] = tb[6];
        const CState before = c_state(e.get());
        CHECK(same_c_state(before, c_state(d)));
        expect_error([&] { (void)e.update_batch(tb, gyr, acc, mag); }, BINGHAM_ERR_INVALID_ARGUMENT,
                     [&] {
                         std::vector<double> qd(4 * n);
                         return bingham_ahrs_update_batch_timed(d, n, tb.data(), gyr.data(), acc.data(), mag.data(),
                                                                qd.data(), nullptr, nullptr);
                     },
                     "a timestamp not after the previous one");
        CHECK(bingham::last_error_message().find("sample 7") != std::string::npos);
        CHECK(same_c_state(c_state(e.get()), c_state(d)) && !same_c_state(before, c_state(e.get())));
        bingham_ahrs_free(d);
        // sizes: t and the rows must agree (before the library is called)
        expect_error([&] { (void)e.update_batch(part(0, 5), rows(gyr, 0, 6), rows(acc, 0, 6), {}); },
                     BINGHAM_ERR_INVALID_DIMENSION, "timed batch size mismatch");
        CHECK(e.update_batch(std::vector<double>{}, {}, {}, {}).empty());
    }
    // a NaN gyroscope sample is a gap: accepted, as by the C call; a finite gyroscope turning by
    // more than 1e6 rad in a sample throws with the C call's status and message, nothing changed
    {
        a.update({std::nan(""), 0.0, 0.1}, {0.3, -0.2, 9.7});
        const std::array<double, 3> gn = {std::nan(""), 0.0, 0.1}, an = {0.3, -0.2, 9.7};
        CHECK_OK(bingham_ahrs_update(c, gn.data(), an.data(), nullptr));
        const CState s = c_state(c);
        CHECK(same_c_state(c_state(a.get()), s) && s.h.gyr_missing_time == dt);
        expect_error([&] { a.update_dt(0.1, {5e7, 0.0, 0.0}, {0.3, -0.2, 9.7}); }, BINGHAM_ERR_INVALID_ARGUMENT,
                     [&] {
                         const double gg[3] = {5e7, 0.0, 0.0};
                         return bingham_ahrs_update_dt(c, 0.1, gg, an.data(), nullptr);
                     },
                     "a gyroscope turning by 5e6 rad");
        CHECK(same_c_state(c_state(a.get()), s) && same_c_state(c_state(c), s));
    }
    // moved-from: the new methods throw BINGHAM_ERR_NULL_ARGUMENT
    bingham::Ahrs moved(std::move(a));
    expect_error([&] { a.update_dt(dt, {0, 0, 0}, {0, 0, 9.81}); }, BINGHAM_ERR_NULL_ARGUMENT, "update_dt, moved-from");
    expect_error([&] { (void)a.update_batch(std::vector<double>{1.0}, {0, 0, 0}, {0, 0, 9.81}, {}); },
                 BINGHAM_ERR_NULL_ARGUMENT, "timed batch, moved-from");
    expect_error([&] { (void)a.orientation_covariance(); }, BINGHAM_ERR_NULL_ARGUMENT,
                 "orientation_covariance, moved-from");
    bingham_ahrs_free(c);
}

static void test_ahrs() {
    const double dt = 0.01;
    bingham::Ahrs a(dt);
    bingham_ahrs_params p;
    CHECK_OK(bingham_ahrs_params_default(dt, &p));
    const bingham::AhrsParams pw = bingham::ahrs_default_params(dt);
    CHECK(std::memcmp(&p, &pw, sizeof p) == 0);
    bingham_ahrs *c = nullptr;
    CHECK_OK(bingham_ahrs_new(&p, &c));
    std::vector<double> gyr, acc, mag;
    for (int k = 0; k < 50; ++k) {
        const std::array<double, 3> g = {0.1, -0.05, 0.2 * std::sin(0.1 * k)}, ac = {0.3, -0.2, 9.7},
                                    mg = {0.1, 20.0, -40.0};
        a.update(g, ac, mg);
        CHECK_OK(bingham_ahrs_update(c, g.data(), ac.data(), mg.data()));
        gyr.insert(gyr.end(), g.begin(), g.end());
        acc.insert(acc.end(), ac.begin(), ac.end());
        mag.insert(mag.end(), mg.begin(), mg.end());
    }
    a.update({0, 0, 0}, {0, 0, 9.81});
    CHECK_OK(bingham_ahrs_update(c, std::array<double, 3>{0, 0, 0}.data(), std::array<double, 3>{0, 0, 9.81}.data(),
                                 nullptr));
    double q[4], m[16], z[4], sp[4], bias[3];
    CHECK_OK(bingham_ahrs_quaternion(c, q));
    CHECK_OK(bingham_ahrs_state(c, m, z));
    CHECK_OK(bingham_ahrs_angular_spread(c, sp));
    CHECK_OK(bingham_ahrs_gyro_bias(c, bias));
    const bingham::Quaternion aq = a.quaternion();
    CHECK(aq.w == q[0] && aq.x == q[1] && aq.y == q[2] && aq.z == q[3]);
    CHECK(same(a.state(), bingham::Distribution(std::vector<double>(m, m + 16), std::vector<double>(z, z + 4))));
    const auto asp = a.angular_spread();
    const auto ab = a.gyro_bias();
    CHECK(std::memcmp(asp.data(), sp, sizeof sp) == 0 && a.uncertainty() == sp[3]);
    CHECK(std::memcmp(ab.data(), bias, sizeof bias) == 0);
    // the scale-error estimate: bit for bit the C call's
    double scale[3];
    CHECK_OK(bingham_ahrs_gyro_scale(c, scale));
    const auto as = a.gyro_scale();
    CHECK(std::memcmp(as.data(), scale, sizeof scale) == 0);
    // the bias covariance: bit for bit the C call's, row-major; bias_std^2 * I on creation
    double cov[9];
    CHECK_OK(bingham_ahrs_gyro_bias_covariance(c, cov));
    const std::array<double, 9> acov = a.gyro_bias_covariance();
    CHECK(std::memcmp(acov.data(), cov, sizeof cov) == 0);
    {
        const std::array<double, 9> c0 = bingham::Ahrs(pw).gyro_bias_covariance();
        for (std::size_t i = 0; i < 9; ++i)
            CHECK(c0[i] == (i % 4 == 0 ? pw.bias_std * pw.bias_std : 0.0));
    }
    // the health readout: the C call's, field by field; all zero on a fresh AHRS
    {
        bingham_ahrs_health_report hc;
        std::memset(&hc, 0xA5, sizeof hc);
        CHECK_OK(bingham_ahrs_health(c, &hc));
        const bingham_ahrs_health_report hw = a.health();
        CHECK(same_health(hw, hc));
        CHECK(hw.has_mag_reference == 1 &&
              hw.score == std::fmax(hw.gravity_score, std::fmax(hw.tilt_score, hw.heading_score)));
        const bingham_ahrs_health_report h0 = bingham::Ahrs(pw).health();
        CHECK(h0.score == 0 && h0.gravity_score == 0 && h0.tilt_score == 0 && h0.heading_score == 0 &&
              h0.tilt_innovation == 0 && h0.heading_innovation == 0 && h0.mag_rejected == 0 && h0.mag_dip == 0 &&
              h0.has_mag_reference == 0 && h0.gyr_missing_time == 0 && h0.acc_missing_time == 0 &&
              h0.mag_missing_time == 0);
        // the last sample had no magnetometer: its missing time is one sample_time
        CHECK(hw.mag_missing_time == dt && hw.gyr_missing_time == 0 && hw.acc_missing_time == 0);
    }
    // the latency readout: none yet after 51 samples (nullopt for BINGHAM_ERR_NOT_CONVERGED)
    double lat = -1.0;
    CHECK(bingham_ahrs_mag_latency_estimate(c, &lat) == BINGHAM_ERR_NOT_CONVERGED && lat == -1.0);
    CHECK(!a.mag_latency_estimate().has_value());
    CHECK(pw.mag_latency == BINGHAM_AHRS_LATENCY_ESTIMATE && pw.acc_latency == 0.0);

    // a refused sample (a gyroscope turning by more than 1e6 rad in the sample) throws and
    // leaves the AHRS unchanged
    const bingham::Distribution before = a.state();
    expect_error([&] { a.update({0, 0, 1e12}, {0, 0, 9.81}); }, BINGHAM_ERR_INVALID_ARGUMENT,
                 [&] {
                     const double gg[3] = {0, 0, 1e12}, aa[3] = {0, 0, 9.81};
                     return bingham_ahrs_update(c, gg, aa, nullptr);
                 },
                 "AHRS sample turning too far");
    CHECK(same(a.state(), before));
    expect_error([] { bingham::Ahrs bad(-1.0); }, BINGHAM_ERR_INVALID_ARGUMENT,
                 [] {
                     bingham_ahrs_params pp;
                     return bingham_ahrs_params_default(-1.0, &pp);
                 },
                 "negative sample time");
    // a rate in Hz where the period is expected: refused with the hint; from_rate takes the rate
    expect_error([] { bingham::Ahrs bad(100.0); }, BINGHAM_ERR_INVALID_ARGUMENT,
                 [] {
                     bingham_ahrs_params pp;
                     return bingham_ahrs_params_default(100.0, &pp);
                 },
                 "a rate passed as the sample time");
    CHECK(bingham::last_error_message().find("did you pass a rate in Hz?") != std::string::npos);
    {
        const bingham::AhrsParams pr = bingham::ahrs_params_from_rate(100.0);
        CHECK(pr.sample_time == 0.01 && std::memcmp(&pr, &pw, sizeof pr) == 0);
        bingham::Ahrs r = bingham::Ahrs::from_rate(100.0);
        r.update({0.1, -0.05, 0.2}, {0.3, -0.2, 9.7}, {0.1, 20.0, -40.0});
        bingham::Ahrs s = bingham::Ahrs(dt);
        s.update({0.1, -0.05, 0.2}, {0.3, -0.2, 9.7}, {0.1, 20.0, -40.0});
        const bingham::Quaternion qr = r.quaternion(), qs = s.quaternion();
        CHECK(qr.w == qs.w && qr.x == qs.x && qr.y == qs.y && qr.z == qs.z);
        CHECK(bingham::Ahrs::from_rate(1.0).gyro_bias_covariance()[0] == pw.bias_std * pw.bias_std);
    }
    for (const double hz : {0.5, 0.0, -100.0, std::nan(""), HUGE_VAL}) {
        expect_error([hz] { bingham::Ahrs::from_rate(hz); }, BINGHAM_ERR_INVALID_ARGUMENT,
                     [hz] {
                         bingham_ahrs_params pp;
                         return bingham_ahrs_params_from_rate(hz, &pp);
                     },
                     "a bad sample rate");
        CHECK(bingham::last_error_message().find("`hz`") != std::string::npos);
    }
    bingham::AhrsParams bad_p = pw;
    bad_p.acc_noise = -1;
    expect_error([&] { bingham::Ahrs bad(bad_p); }, BINGHAM_ERR_INVALID_ARGUMENT,
                 [&] {
                     bingham_ahrs *x = nullptr;
                     return bingham_ahrs_new(&bad_p, &x);
                 },
                 "bad parameter");
    expect_error([&] { bingham::Distribution s2 = bingham::noise_from_angle_std(2, 0.1); a.set_state(s2); },
                 BINGHAM_ERR_INVALID_DIMENSION, "set_state with d = 2");

    // batch = one by one; clone independent; set_state
    bingham::Ahrs fresh(pw);
    bingham::Ahrs copy = fresh.clone();
    const std::vector<double> quats = fresh.update_batch(gyr, acc, mag);
    CHECK(quats.size() == 200);
    for (std::size_t k = 0; k < 50; ++k) {
        copy.update({gyr[3 * k], gyr[3 * k + 1], gyr[3 * k + 2]}, {acc[3 * k], acc[3 * k + 1], acc[3 * k + 2]},
                    {mag[3 * k], mag[3 * k + 1], mag[3 * k + 2]});
        const bingham::Quaternion qk = copy.quaternion();
        CHECK(qk.w == quats[4 * k] && qk.x == quats[4 * k + 1] && qk.y == quats[4 * k + 2] &&
              qk.z == quats[4 * k + 3]);
    }
    bingham::Ahrs other = copy.clone();
    other.update({1, 0, 0}, {0, 0, 9.81});
    CHECK(same(copy.state(), fresh.state()) && !same(other.state(), copy.state()));
    expect_error([&] { (void)fresh.update_batch(gyr, acc, {1.0}); }, BINGHAM_ERR_INVALID_DIMENSION,
                 "batch size mismatch");
    other.set_state(before);
    CHECK(same(other.state(), before));

    // move
    bingham::Ahrs moved(std::move(a));
    CHECK(!a && static_cast<bool>(moved) && same(moved.state(), before));
    expect_error([&] { (void)a.quaternion(); }, BINGHAM_ERR_NULL_ARGUMENT, "moved-from AHRS");
    expect_error([&] { (void)a.gyro_bias_covariance(); }, BINGHAM_ERR_NULL_ARGUMENT, "moved-from AHRS");
    expect_error([&] { (void)a.health(); }, BINGHAM_ERR_NULL_ARGUMENT, "health of a moved-from AHRS");
    a = std::move(other);
    moved = std::move(a);
    CHECK(!a && static_cast<bool>(moved) && same(moved.state(), before));
    bingham_ahrs_free(c);
}

// bingham::smooth and bingham::smooth_ex: bit for bit the C calls; a wrong shape and a refused
// recording throw with the C call's status and message.
static void test_smooth() {
    const int n = 250;
    std::vector<double> gyr(3 * n), acc(3 * n), mag(3 * n), t(n);
    for (int k = 0; k < n; ++k) {
        std::array<double, 3> g, ac, mg;
        ahrs_sample(k, g, ac, mg);
        for (int i = 0; i < 3; ++i) gyr[3 * k + i] = g[i], acc[3 * k + i] = ac[i], mag[3 * k + i] = mg[i];
        t[k] = 7.0 + 0.01 * k + (k % 3 == 0 ? 0.002 : 0.0);
    }
    const bingham::AhrsParams p = bingham::ahrs_default_params(0.01);
    const std::vector<double> q = bingham::smooth(p, gyr, acc, mag);
    std::vector<double> qc(4 * n);
    CHECK_OK(bingham_ahrs_smooth(&p, n, gyr.data(), acc.data(), mag.data(), qc.data(), nullptr));
    CHECK(same(q, qc));
    const std::vector<double> q6 = bingham::smooth(p, gyr, acc);
    CHECK_OK(bingham_ahrs_smooth(&p, n, gyr.data(), acc.data(), nullptr, qc.data(), nullptr));
    CHECK(same(q6, qc));
    const bingham::Smoothed r = bingham::smooth_ex(p, t, gyr, acc, mag);
    std::vector<double> sc(n), bc(3 * n), cc(9 * n);
    CHECK_OK(bingham_ahrs_smooth_ex(&p, n, t.data(), gyr.data(), acc.data(), mag.data(), qc.data(), sc.data(),
                                    bc.data(), cc.data()));
    CHECK(same(r.quat, qc) && same(r.spread, sc) && same(r.bias, bc) && same(r.covariance, cc));
    CHECK(bingham::smooth(p, {}, {}).empty());
    expect_error([&] { (void)bingham::smooth(p, gyr, std::vector<double>(3)); }, BINGHAM_ERR_INVALID_DIMENSION,
                 "smooth: acc of another length");
    std::vector<double> bad = acc;
    bad[2] = std::nan("");
    bad[0] = bad[1] = 0.0;
    expect_error([&] { (void)bingham::smooth(p, gyr, bad, mag); }, BINGHAM_ERR_INVALID_ARGUMENT,
                 [&] { return bingham_ahrs_smooth(&p, n, gyr.data(), bad.data(), mag.data(), qc.data(), nullptr); },
                 "smooth: a first sample without gravity");
}

int main() {
    try {
        test_free_functions();
        test_filter();
        test_filter_nonlinear();
        test_filter_world();
        test_spin_filter();
        test_ahrs();
        test_ahrs_timing();
        test_smooth();
    } catch (const std::exception &e) {
        std::fprintf(stderr, "unexpected exception: %s\n", e.what());
        return 1;
    }
    return check_summary(__cplusplus >= 202002L ? "wrapper_plain (C++20)" : "wrapper_plain (C++17)");
}
