/* The C API of the vector observations, rotation noise, angular spread and the AHRS
 * (bingham_vector_observation, bingham_noise_from_angle_std, bingham_angular_spread,
 * bingham_filter_update_vector / _log_likelihood_vector / _angular_spread, bingham_ahrs_*):
 *
 * - the success path of every function;
 * - every pointer argument set to NULL -> BINGHAM_ERR_NULL_ARGUMENT with a message naming the
 *   function and the argument ("`body` is NULL"); optional ones (mag, spread) accepted;
 * - NaN/Inf in every vector entry, non-unit vectors just outside the 1e-6 tolerance (just
 *   inside: accepted), kappa negative/NaN/Inf, sigma 0/negative/NaN/Inf/tiny, d = 3 (with the
 *   arrays aimed at an inaccessible page), a d = 2 filter for update_vector -> the documented
 *   status;
 * - after every failure: outputs byte-for-byte unchanged (sentinel fill), filter / AHRS state
 *   identical (quaternion, M, z, bias, spread);
 * - the AHRS: NaN/Inf in any entry of a gyroscope, accelerometer or magnetometer sample
 *   accepted as "no sample" of that sensor (one non-finite gyroscope entry the same as a NaN
 *   row, a non-finite field the same as mag = NULL, bit for bit; the health readout's
 *   gyr/acc/mag_missing_time growing by sample_time per missing row and back to 0 after a
 *   usable one), a finite gyroscope turning by more than 1e6 rad in a sample refused (state
 *   unchanged, also the hidden state: a clone taken before evolves identically), a first
 *   sample without a finite accelerometer showing gravity refused, params with sample_time
 *   0/NaN refused, a batch running through NaN gyroscope, accelerometer and magnetometer rows
 *   (rows equal to single updates) and stopping at a huge gyroscope row in sample 5 of 10
 *   (message "sample 5", rows 0..4 written and equal to single updates, rows 5..9 untouched),
 *   a batch whose first sample has a NaN accelerometer refused at "sample 0", mag = NULL
 *   accepted, bingham_ahrs_free(NULL), clones evolving identically;
 * - bingham_ahrs_update_dt: NULLs with the message naming the argument; dt 0, negative,
 *   NaN/Inf, below BINGHAM_AHRS_MIN_SAMPLE_TIME, above BINGHAM_AHRS_MAX_STEP_TIME refused with
 *   the AHRS unchanged (getters, health readout, and a clone taken before evolving identically
 *   afterwards), also before the first sample; the bounds themselves accepted;
 *   update_dt(sample_time) == update bit for bit over a stream with NaN rows (from a fresh AHRS
 *   and mid-stream); another dt is used (a different estimate); the gyroscope's turn limit
 *   applied to |gyr| * dt; a gap of NaN gyroscope rows in motion widening the spread beyond
 *   the same samples with the gyroscope present;
 * - bingham_ahrs_update_batch_timed: uniformly spaced timestamps == bingham_ahrs_update_batch_health
 *   bit for bit (quaternions, spread, health, final state; mag/spread/health NULL or not; NaN
 *   rows in every channel processed); with jitter and dropped samples, a batch split anywhere
 *   (pieces of 1, 0, 7, ... samples) == one call; the step of t[0]: from the previous timed
 *   batch's last timestamp (== update_dt with that difference), sample_time on a fresh AHRS
 *   and after an untimed update (== update); a timestamp NaN/Inf, equal to or before the
 *   previous one, or a step above 10 s or below 1e-6 s stops the batch at that sample
 *   ("sample 5": rows 0..4 written and equal to a reference, rows 5.. of quat, spread and
 *   health untouched, the AHRS in the state after sample 4, the last timestamp t[4] kept); a
 *   step of exactly 10 s accepted; a t[0] not after the previous batch's last timestamp
 *   refused at "sample 0" with nothing written; NULLs, n = 0, n * 4 overflowing;
 * - bingham_ahrs_orientation_covariance: the identity before the first sample; NULLs (output
 *   untouched); after samples (with and without magnetometer, mid correction period, after
 *   set_state) symmetric, positive semi-definite (principal minors), trace == spread[3]^2
 *   within 1e-12 relative; in the world frame: a tilted sensor without magnetometer has its
 *   unknown heading as the variance about world z (up), not about the sensor's z axis;
 * - the gyroscope bias's uncertainty: the defaults bias_std = 0.5 deg/s and
 *   gyro_scale_noise >= 0; bias_std NaN/negative/0 and gyro_scale_noise NaN/negative refused by
 *   bingham_ahrs_new with a message naming the field; bingham_ahrs_gyro_bias_covariance: NULLs
 *   (output untouched), bias_std^2 I on creation, after 30 s of a turning stream symmetric with
 *   a positive diagonal below bias_std^2;
 * - the latencies: default 0, out-of-range / NaN mag_latency and acc_latency refused with a
 *   message naming the field; bingham_ahrs_mag_latency_estimate: NULLs, NOT_CONVERGED (output
 *   untouched) before informative motion, then the delay of a noise-free simulated spin with a
 *   changing rate and the magnetometer two samples late.
 * - bingham_ahrs_smooth / _ex: a slow turn about z smoothed within 1 degree of the truth, unit
 *   quaternions with w >= 0, the last row the online AHRS's bit for bit (n = 1 too); _ex with
 *   uniformly spaced timestamps == the untimed call bit for bit, spread == sqrt(trace cov),
 *   covariances symmetric, the bias finite; NaN rows and mag NULL processed; NULLs, a first
 *   sample without gravity, a huge gyroscope row, a timestamp not increasing, a bad parameter,
 *   n * 4 overflowing (arrays on an inaccessible page) refused with every output untouched;
 *   n = 0 writes nothing.
 * - the health readout (bingham_ahrs_health): all zero before the first sample; after 5 s of the
 *   slow turn every field finite, score == max(gravity_score, tilt_score, heading_score),
 *   0 <= mag_rejected <= 1, a reference with the dip of the simulated field (atan(40/20) below
 *   the horizon, positive; negative with the accelerometer's sign flipped), below
 *   BINGHAM_AHRS_HEALTH_THRESHOLD; without a magnetometer no reference, no heading score;
 *   NULL `a` / `out` refused with the output untouched; the missing times: 0 before and after
 *   the first sample, the magnetometer's counted from the first sample when none is ever
 *   given, free fall and a zero field counted as missing, update_dt's and a timed batch's
 *   steps added;
 * - bingham_ahrs_update_batch_health (from a fresh AHRS and mid-stream, with spread and health
 *   each present or NULL, mag NULL): quaternions bit for bit the single updates', spread[k] the
 *   total spread and health[k] bingham_ahrs_health's score after sample k (NaN gyroscope rows
 *   among the samples); a gyroscope row turning by more than 1e6 rad in sample 5 stops it there
 *   (rows 5.. untouched); NULLs refused, nothing written.
 *
 * bingham_ahrs_params is filled with bingham_ahrs_params_default() only (its fields may change);
 * only sample_time, the latencies, bias_std and gyro_scale_noise are set by hand.
 */
#define _DEFAULT_SOURCE 1
#include <float.h>
#include <stdint.h>
#include <stdlib.h>

#include "check.h"
#include "api_util.h"

static const double PI = 3.14159265358979323846;

/* The last message starts with "<fn>: " and contains `needle` (if not NULL). */
#define check_msg(fn, needle) CHECK_MESSAGE(fn, needle)

static void check_null_msg(const char *fn, const char *arg) { check_msg(fn, null_needle(arg)); }

#define SENT 0xA5
static void fill(void *p, size_t bytes) { memset(p, SENT, bytes); }
static int untouched(const void *p, size_t bytes) {
    const unsigned char *c = (const unsigned char *)p;
    for (size_t i = 0; i < bytes; ++i)
        if (c[i] != SENT) return 0;
    return 1;
}

static int all_finite(const double *v, size_t n) {
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(v[i])) return 0;
    return 1;
}

/* ---- bingham_vector_observation ---------------------------------------------------------- */

static void test_vector_observation(void) {
    const char *fn = "bingham_vector_observation";
    double b[3] = {0.3, -0.5, 0.8}, r[3] = {0.1, 0.2, -0.9}, m[16], z[4];
    normalize(b, 3);
    normalize(r, 3);
    CHECK_OK(bingham_vector_observation(b, r, 4.0, m, z));
    CHECK(all_finite(m, 16) && z[0] == -8.0 && z[1] == -8.0 && z[2] == 0.0 && z[3] == 0.0);
    CHECK_OK(bingham_vector_observation(b, r, 0.0, m, z));
    CHECK(z[0] == 0.0 && z[1] == 0.0 && z[2] == 0.0 && z[3] == 0.0);
    /* NULLs */
    const double *ins[2] = {b, r};
    const char *in_names[2] = {"body", "reference"};
    for (int k = 0; k < 4; ++k) {
        const double *bb = k == 0 ? NULL : ins[0], *rr = k == 1 ? NULL : ins[1];
        double *mm = k == 2 ? NULL : m, *zz = k == 3 ? NULL : z;
        fill(m, sizeof m);
        fill(z, sizeof z);
        CHECK_STATUS(bingham_vector_observation(bb, rr, 1.0, mm, zz), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK(untouched(m, sizeof m) && untouched(z, sizeof z));
        check_null_msg(fn, k < 2 ? in_names[k] : (k == 2 ? "m" : "z"));
    }
    /* NaN / Inf in each entry of each vector */
    const double bad[3] = {NAN, INFINITY, -INFINITY};
    for (int which = 0; which < 2; ++which)
        for (int i = 0; i < 3; ++i)
            for (int v = 0; v < 3; ++v) {
                double bb[3], rr[3];
                memcpy(bb, b, sizeof bb);
                memcpy(rr, r, sizeof rr);
                (which ? rr : bb)[i] = bad[v];
                fill(m, sizeof m);
                fill(z, sizeof z);
                CHECK_STATUS(bingham_vector_observation(bb, rr, 1.0, m, z), BINGHAM_ERR_INVALID_ARGUMENT);
                CHECK(untouched(m, sizeof m) && untouched(z, sizeof z));
                check_msg(fn, in_names[which]);
            }
    /* non-unit: just outside / inside the tolerance, zero vector, huge */
    for (int which = 0; which < 2; ++which) {
        const double scales[4] = {1 + 2e-3, 1 - 2e-3, 0.0, 1e300}; /* beyond BINGHAM_UNIT_TOL */
        for (int s = 0; s < 4; ++s) {
            double bb[3], rr[3];
            memcpy(bb, b, sizeof bb);
            memcpy(rr, r, sizeof rr);
            for (int i = 0; i < 3; ++i) (which ? rr : bb)[i] *= scales[s];
            fill(m, sizeof m);
            fill(z, sizeof z);
            CHECK_STATUS(bingham_vector_observation(bb, rr, 1.0, m, z), BINGHAM_ERR_INVALID_ARGUMENT);
            CHECK(untouched(m, sizeof m) && untouched(z, sizeof z));
            check_msg(fn, "unit");
        }
        double bb[3], rr[3];
        memcpy(bb, b, sizeof bb);
        memcpy(rr, r, sizeof rr);
        for (int i = 0; i < 3; ++i) (which ? rr : bb)[i] *= 1 + 1e-8;
        CHECK_OK(bingham_vector_observation(bb, rr, 1.0, m, z));
    }
    /* kappa: negative, NaN, +-Inf */
    const double bad_kappa[5] = {-1.0, -1e-300, NAN, INFINITY, -INFINITY};
    for (int k = 0; k < 5; ++k) {
        fill(m, sizeof m);
        fill(z, sizeof z);
        CHECK_STATUS(bingham_vector_observation(b, r, bad_kappa[k], m, z), BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK(untouched(m, sizeof m) && untouched(z, sizeof z));
        check_msg(fn, "kappa");
    }
}

/* ---- bingham_noise_from_angle_std ---------------------------------------------------------- */

static void test_noise_from_angle_std(void) {
    const char *fn = "bingham_noise_from_angle_std";
    double m[16], z[4];
    for (size_t d = 2; d <= 4; d += 2) {
        CHECK_OK(bingham_noise_from_angle_std(d, 0.1, m, z));
        CHECK(all_finite(m, d * d) && z[d - 1] == 0.0 && z[0] < 0.0 && m[d - 1] == 1.0);
        fill(m, sizeof m);
        fill(z, sizeof z);
        CHECK_STATUS(bingham_noise_from_angle_std(d, 0.1, NULL, z), BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "m");
        CHECK_STATUS(bingham_noise_from_angle_std(d, 0.1, m, NULL), BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "z");
        CHECK(untouched(m, sizeof m) && untouched(z, sizeof z));
        const double bad[7] = {0.0, -0.0, -0.1, NAN, INFINITY, -INFINITY, 1e-9};
        for (int k = 0; k < 7; ++k) {
            CHECK_STATUS(bingham_noise_from_angle_std(d, bad[k], m, z), BINGHAM_ERR_INVALID_ARGUMENT);
            CHECK(untouched(m, sizeof m) && untouched(z, sizeof z));
            /* (below ~6e-7 rad the message speaks of the singular second moment, not of sigma) */
            check_msg(fn, bad[k] == 1e-9 ? NULL : "sigma");
        }
        /* large sigma: still a valid (nearly uniform) distribution */
        CHECK_OK(bingham_noise_from_angle_std(d, 50.0, m, z));
        CHECK(all_finite(m, d * d) && all_finite(z, d) && z[d - 1] == 0.0);
    }
    const size_t bad_d[5] = {0, 1, 3, 5, (size_t)-1};
    for (int k = 0; k < 5; ++k) {
        CHECK_STATUS(bingham_noise_from_angle_std(bad_d[k], 0.1, no_access(), no_access()),
                     BINGHAM_ERR_INVALID_DIMENSION);
        check_msg(fn, "d = ");
        CHECK_STATUS(bingham_noise_from_angle_std(bad_d[k], NAN, NULL, NULL), BINGHAM_ERR_INVALID_DIMENSION);
    }
}

/* ---- bingham_angular_spread ---------------------------------------------------------------- */

static void test_angular_spread(void) {
    const char *fn = "bingham_angular_spread";
    const double m4[16] = {0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 0};
    const double z4[4] = {-400, -100, -25, 0};
    double sp[4];
    CHECK_OK(bingham_angular_spread(4, m4, z4, sp));
    CHECK(all_finite(sp, 4) && sp[0] < sp[1] && sp[1] < sp[2] && sp[2] < sp[3]);
    CHECK_CLOSE(sp[0] * sp[0] + sp[1] * sp[1] + sp[2] * sp[2], sp[3] * sp[3], 1e-12);
    const double m2[4] = {0, 1, 1, 0}, z2[2] = {-50, 0};
    CHECK_OK(bingham_angular_spread(2, m2, z2, sp));
    CHECK(all_finite(sp, 2) && sp[0] > 0);
    /* uniform: total 2 sqrt(3/4) (d = 4) */
    const double zu[4] = {0, 0, 0, 0};
    CHECK_OK(bingham_angular_spread(4, m4, zu, sp));
    CHECK_CLOSE(sp[3], sqrt(3.0), 1e-12);
    /* NULLs */
    fill(sp, sizeof sp);
    CHECK_STATUS(bingham_angular_spread(4, NULL, z4, sp), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fn, "m");
    CHECK_STATUS(bingham_angular_spread(4, m4, NULL, sp), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fn, "z");
    CHECK_STATUS(bingham_angular_spread(4, m4, z4, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fn, "spread");
    CHECK(untouched(sp, sizeof sp));
    /* NaN / Inf anywhere in m or z */
    for (int i = 0; i < 20; ++i) {
        double mm[16], zz[4];
        memcpy(mm, m4, sizeof mm);
        memcpy(zz, z4, sizeof zz);
        if (i < 16) mm[i] = i % 2 ? NAN : INFINITY;
        else zz[i - 16] = i % 2 ? NAN : -INFINITY;
        CHECK_STATUS(bingham_angular_spread(4, mm, zz, sp), BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK(untouched(sp, sizeof sp));
        check_msg(fn, i < 16 ? "m[" : "z[");
    }
    /* not orthogonal */
    double mm[16];
    memcpy(mm, m4, sizeof mm);
    mm[3] += 1e-4;
    CHECK_STATUS(bingham_angular_spread(4, mm, z4, sp), BINGHAM_ERR_INVALID_ARGUMENT);
    CHECK(untouched(sp, sizeof sp));
    check_msg(fn, "orthogonal");
    /* d = 3 and other bad d: refused before any access */
    const size_t bad_d[5] = {0, 1, 3, 5, 65};
    for (int k = 0; k < 5; ++k) {
        CHECK_STATUS(bingham_angular_spread(bad_d[k], no_access(), no_access(), no_access()),
                     BINGHAM_ERR_INVALID_DIMENSION);
        check_msg(fn, "d = ");
    }
}

/* ---- the filter with vectors ---------------------------------------------------------------- */

static void test_filter_vector(void) {
    const double m0[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    const double z0[4] = {-20, -10, -5, 0};
    double b[3] = {0.2, 0.1, 0.97}, r[3] = {0, 0, 1};
    normalize(b, 3);
    bingham_filter *f = NULL, *f2 = NULL;
    CHECK_OK(bingham_filter_new(4, m0, z0, &f));
    const double m2[4] = {1, 0, 0, 1}, z2[2] = {-3, 0};
    CHECK_OK(bingham_filter_new(2, m2, z2, &f2));
    if (!f || !f2) return;

    /* success paths */
    double ll = 0, sp[4];
    CHECK_OK(bingham_filter_log_likelihood_vector(f, b, r, 10.0, &ll));
    CHECK(isfinite(ll));
    CHECK_OK(bingham_filter_angular_spread(f, sp));
    CHECK(all_finite(sp, 4) && sp[3] > 0);
    double before_total = sp[3];
    CHECK_OK(bingham_filter_update_vector(f, b, r, 100.0));
    CHECK_OK(bingham_filter_angular_spread(f, sp));
    CHECK(sp[3] < before_total); /* an observation sharpens the state */
    double sp2[3];
    fill(sp2, sizeof sp2);
    CHECK_OK(bingham_filter_angular_spread(f2, sp2));
    CHECK(all_finite(sp2, 2) && untouched(&sp2[2], sizeof(double))); /* d = 2: exactly 2 written */

    snapshot s0;
    CHECK_OK(snap_status(f, &s0));
    /* update_vector: NULLs */
    const char *fu = "bingham_filter_update_vector", *fl = "bingham_filter_log_likelihood_vector";
    CHECK_STATUS(bingham_filter_update_vector(NULL, b, r, 1.0), BINGHAM_ERR_NULL_ARGUMENT);
    check_msg(fu, "is NULL");
    CHECK_STATUS(bingham_filter_update_vector(f, NULL, r, 1.0), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fu, "body");
    CHECK_STATUS(bingham_filter_update_vector(f, b, NULL, 1.0), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fu, "reference");
    /* log_likelihood_vector: NULLs, out untouched */
    double out = 0;
    fill(&out, sizeof out);
    CHECK_STATUS(bingham_filter_log_likelihood_vector(NULL, b, r, 1.0, &out), BINGHAM_ERR_NULL_ARGUMENT);
    check_msg(fl, "is NULL");
    CHECK_STATUS(bingham_filter_log_likelihood_vector(f, NULL, r, 1.0, &out), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fl, "body");
    CHECK_STATUS(bingham_filter_log_likelihood_vector(f, b, NULL, 1.0, &out), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fl, "reference");
    CHECK_STATUS(bingham_filter_log_likelihood_vector(f, b, r, 1.0, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fl, "out");
    CHECK(untouched(&out, sizeof out));
    /* angular_spread: NULLs */
    fill(sp, sizeof sp);
    CHECK_STATUS(bingham_filter_angular_spread(NULL, sp), BINGHAM_ERR_NULL_ARGUMENT);
    check_msg("bingham_filter_angular_spread", "is NULL");
    CHECK_STATUS(bingham_filter_angular_spread(f, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_filter_angular_spread", "spread");
    CHECK(untouched(sp, sizeof sp));

    /* NaN / Inf, non-unit, bad kappa: both functions, state and out untouched */
    const double bad[3] = {NAN, INFINITY, -INFINITY};
    for (int which = 0; which < 2; ++which)
        for (int i = 0; i < 3; ++i)
            for (int v = 0; v < 4; ++v) {
                double bb[3], rr[3];
                memcpy(bb, b, sizeof bb);
                memcpy(rr, r, sizeof rr);
                double *t = which ? rr : bb;
                if (v < 3) t[i] = bad[v];
                else for (int k = 0; k < 3; ++k) t[k] *= 1 + 2e-3; /* non-unit (beyond BINGHAM_UNIT_TOL) */
                CHECK_STATUS(bingham_filter_update_vector(f, bb, rr, 5.0), BINGHAM_ERR_INVALID_ARGUMENT);
                check_msg(fu, which ? "reference" : "body");
                CHECK_STATUS(bingham_filter_log_likelihood_vector(f, bb, rr, 5.0, &out), BINGHAM_ERR_INVALID_ARGUMENT);
                check_msg(fl, which ? "reference" : "body");
                CHECK(untouched(&out, sizeof out));
            }
    const double bad_kappa[4] = {-1.0, NAN, INFINITY, -INFINITY};
    for (int k = 0; k < 4; ++k) {
        CHECK_STATUS(bingham_filter_update_vector(f, b, r, bad_kappa[k]), BINGHAM_ERR_INVALID_ARGUMENT);
        check_msg(fu, "kappa");
        CHECK_STATUS(bingham_filter_log_likelihood_vector(f, b, r, bad_kappa[k], &out), BINGHAM_ERR_INVALID_ARGUMENT);
        check_msg(fl, "kappa");
        CHECK(untouched(&out, sizeof out));
    }
    snapshot s1;
    CHECK_OK(snap_status(f, &s1));
    CHECK(same(s0, s1));

    /* a d = 2 filter: INVALID_DIMENSION, state unchanged */
    snapshot t0, t1;
    CHECK_OK(snap_status(f2, &t0));
    CHECK_STATUS(bingham_filter_update_vector(f2, b, r, 1.0), BINGHAM_ERR_INVALID_DIMENSION);
    check_msg(fu, "d = 2");
    CHECK_STATUS(bingham_filter_log_likelihood_vector(f2, b, r, 1.0, &out), BINGHAM_ERR_INVALID_DIMENSION);
    check_msg(fl, "d = 2");
    CHECK(untouched(&out, sizeof out));
    CHECK_OK(snap_status(f2, &t1));
    CHECK(same(t0, t1));

    /* kappa = 0: no information, the state stays */
    CHECK_OK(bingham_filter_update_vector(f, b, r, 0.0));
    snapshot s2;
    CHECK_OK(snap_status(f, &s2));
    for (int i = 0; i < 4; ++i) CHECK_CLOSE(s2.z[i], s0.z[i], 1e-12);
    /* huge kappa: a sharp state or NUMERICAL, never a broken state */
    int st = (int)bingham_filter_update_vector(f, b, r, 1e300);
    CHECK(st == BINGHAM_OK || st == BINGHAM_ERR_NUMERICAL);
    snapshot s3;
    CHECK_OK(snap_status(f, &s3));
    CHECK(all_finite(s3.m, 16) && all_finite(s3.z, 4) && s3.z[3] == 0.0);
    if (st != BINGHAM_OK) CHECK(same(s2, s3));
    bingham_filter_free(f);
    bingham_filter_free(f2);
}

/* ---- the AHRS ------------------------------------------------------------------------------- */

/* Everything the getters show (the health readout's doubles included), for bit-for-bit
 * comparisons. */
typedef struct {
    double q[4], m[16], z[4], bias[3], scale[3], spread[4], cov[9], ocov[9], health[12];
} astate; /* doubles only: no padding for memcmp to trip on */

static astate asnap(const bingham_ahrs *a) {
    astate s;
    bingham_ahrs_health_report h;
    memset(&s, 0, sizeof s);
    memset(&h, 0, sizeof h);
    CHECK_OK(bingham_ahrs_quaternion(a, s.q));
    CHECK_OK(bingham_ahrs_state(a, s.m, s.z));
    CHECK_OK(bingham_ahrs_gyro_bias(a, s.bias));
    CHECK_OK(bingham_ahrs_gyro_scale(a, s.scale));
    CHECK_OK(bingham_ahrs_angular_spread(a, s.spread));
    CHECK_OK(bingham_ahrs_gyro_bias_covariance(a, s.cov));
    CHECK_OK(bingham_ahrs_orientation_covariance(a, s.ocov));
    CHECK_OK(bingham_ahrs_health(a, &h));
    /* field by field: the struct's padding is not compared */
    const double hv[12] = {h.score,           h.gravity_score,      h.tilt_score,       h.heading_score,
                           h.tilt_innovation, h.heading_innovation, h.mag_rejected,     h.mag_dip,
                           h.gyr_missing_time, h.acc_missing_time,  h.mag_missing_time, (double)h.has_mag_reference};
    memcpy(s.health, hv, sizeof hv);
    return s;
}

static int same_state(astate a, astate b) { return memcmp(&a, &b, sizeof a) == 0; }

/* Sample k of a slow rotation about z with gravity and a northern field (sensor frame). */
static void sample(int k, double *g, double *acc, double *mag) {
    double t = 0.01 * k, yaw = 0.3 * t, c = cos(yaw), s = sin(yaw);
    g[0] = 0.001, g[1] = -0.002, g[2] = 0.3;
    acc[0] = 0.0, acc[1] = 0.0, acc[2] = 9.81;
    /* world field (0, 20, -40) seen by a sensor rotated by yaw about z: R^T (0, 20, -40) */
    mag[0] = s * 20.0, mag[1] = c * 20.0, mag[2] = -40.0;
}

static bingham_ahrs *new_ahrs(double dt) {
    bingham_ahrs_params p;
    bingham_ahrs *a = NULL;
    CHECK_OK(bingham_ahrs_params_default(dt, &p));
    CHECK_OK(bingham_ahrs_new(&p, &a));
    return a;
}

static void test_ahrs_params_and_new(void) {
    bingham_ahrs_params p, q;
    const double bad_dt[5] = {0.0, -0.01, NAN, INFINITY, -INFINITY};
    for (int k = 0; k < 5; ++k) {
        fill(&p, sizeof p);
        CHECK_STATUS(bingham_ahrs_params_default(bad_dt[k], &p), BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK(untouched(&p, sizeof p));
        check_msg("bingham_ahrs_params_default", "sample_time");
    }
    CHECK_STATUS(bingham_ahrs_params_default(0.01, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_params_default", "p");
    /* a rate in Hz passed as the period: refused, the message says so and gives the period */
    const double rates[3] = {100.0, 1000.0, 1.5};
    for (int k = 0; k < 3; ++k) {
        fill(&p, sizeof p);
        CHECK_STATUS(bingham_ahrs_params_default(rates[k], &p), BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK(untouched(&p, sizeof p));
        check_msg("bingham_ahrs_params_default", "did you pass a rate in Hz?");
        check_msg("bingham_ahrs_params_default", "bingham_ahrs_params_from_rate(");
    }
    check_msg("bingham_ahrs_params_default", "for 1.5 Hz pass 0.6666");
    CHECK_OK(bingham_ahrs_params_default(BINGHAM_AHRS_MAX_SAMPLE_TIME, &p)); /* the bound itself */
    CHECK(p.sample_time == 1.0 && BINGHAM_AHRS_MAX_SAMPLE_TIME == 1.0);

    /* the rate in Hz: the defaults for the period 1/hz */
    CHECK_OK(bingham_ahrs_params_from_rate(100.0, &p));
    CHECK_OK(bingham_ahrs_params_default(0.01, &q));
    CHECK(p.sample_time == 0.01 && memcmp(&p, &q, sizeof p) == 0);
    CHECK_OK(bingham_ahrs_params_from_rate(400.0, &p));
    CHECK(p.sample_time == 0.0025);
    CHECK_OK(bingham_ahrs_params_from_rate(1.0, &p));
    CHECK(p.sample_time == 1.0);
    const double bad_hz[7] = {0.5, 0.0, -100.0, NAN, INFINITY, -INFINITY, 2e6};
    for (int k = 0; k < 7; ++k) {
        fill(&p, sizeof p);
        CHECK_STATUS(bingham_ahrs_params_from_rate(bad_hz[k], &p), BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK(untouched(&p, sizeof p));
        check_msg("bingham_ahrs_params_from_rate", "`hz`");
    }
    check_msg("bingham_ahrs_params_from_rate", "above 1000000 Hz");
    CHECK_STATUS(bingham_ahrs_params_from_rate(0.5, &p), BINGHAM_ERR_INVALID_ARGUMENT);
    check_msg("bingham_ahrs_params_from_rate", "below 1 Hz");
    CHECK_STATUS(bingham_ahrs_params_from_rate(100.0, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_params_from_rate", "p");
    CHECK_OK(bingham_ahrs_params_default(0.01, &p));
    CHECK(p.sample_time == 0.01);
    CHECK_OK(bingham_ahrs_params_default(0.01, &q));
    CHECK(memcmp(&p, &q, sizeof p) == 0); /* deterministic */

    bingham_ahrs *a = (bingham_ahrs *)no_access();
    CHECK_STATUS(bingham_ahrs_new(NULL, &a), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_new", "p");
    CHECK(a == (bingham_ahrs *)no_access());
    CHECK_STATUS(bingham_ahrs_new(&p, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_new", "out");
    const double bad_st[5] = {0.0, NAN, -1.0, INFINITY, 100.0};
    for (int k = 0; k < 5; ++k) {
        q = p;
        q.sample_time = bad_st[k];
        CHECK_STATUS(bingham_ahrs_new(&q, &a), BINGHAM_ERR_INVALID_ARGUMENT);
        check_msg("bingham_ahrs_new", "sample_time");
        CHECK(a == (bingham_ahrs *)no_access());
    }
    a = NULL;
    CHECK_OK(bingham_ahrs_new(&p, &a));
    CHECK(a != NULL);
    /* before the first sample: identity, uniform state, zero bias */
    astate s = asnap(a);
    CHECK(s.q[0] == 1.0 && s.q[1] == 0.0 && s.q[2] == 0.0 && s.q[3] == 0.0);
    for (int i = 0; i < 4; ++i) CHECK(s.z[i] == 0.0);
    CHECK(s.bias[0] == 0.0 && s.bias[1] == 0.0 && s.bias[2] == 0.0);
    bingham_ahrs_free(a);
    bingham_ahrs_free(NULL); /* no-op */
}

static void test_ahrs_update(void) {
    bingham_ahrs *a = new_ahrs(0.01);
    if (!a) return;
    const char *fn = "bingham_ahrs_update";
    double g[3], acc[3], mag[3];
    sample(0, g, acc, mag);
    /* a first sample without gravity is refused, and the AHRS stays uninitialized */
    astate s0 = asnap(a);
    double zero[3] = {0, 0, 0};
    CHECK_STATUS(bingham_ahrs_update(a, g, zero, mag), BINGHAM_ERR_INVALID_ARGUMENT);
    check_msg(fn, NULL);
    CHECK(same_state(s0, asnap(a)));
    /* so is a first sample without an accelerometer (NaN / Inf): there is no tilt to start from */
    for (int i = 0; i < 3; ++i) {
        double aa[3];
        memcpy(aa, acc, sizeof aa);
        aa[i] = i == 1 ? INFINITY : NAN;
        CHECK_STATUS(bingham_ahrs_update(a, g, aa, mag), BINGHAM_ERR_INVALID_ARGUMENT);
        check_msg(fn, "first sample");
        CHECK(same_state(s0, asnap(a)));
    }
    for (int k = 0; k < 50; ++k) {
        sample(k, g, acc, mag);
        CHECK_OK(bingham_ahrs_update(a, g, acc, mag));
    }
    astate s = asnap(a);
    CHECK(all_finite(s.q, 4) && fabs(s.q[0] * s.q[0] + s.q[1] * s.q[1] + s.q[2] * s.q[2] + s.q[3] * s.q[3] - 1) < 1e-12);
    CHECK(s.q[0] >= 0.0 && s.z[3] == 0.0 && all_finite(s.spread, 4));
    /* NULLs */
    CHECK_STATUS(bingham_ahrs_update(NULL, g, acc, mag), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fn, "a");
    CHECK_STATUS(bingham_ahrs_update(a, NULL, acc, mag), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fn, "gyr");
    CHECK_STATUS(bingham_ahrs_update(a, g, NULL, mag), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fn, "acc");
    CHECK(same_state(s, asnap(a)));
    /* NaN / Inf in any entry of the gyroscope sample: "no gyroscope sample" (a gap), accepted
     * (on clones): the same as a NaN row, bit for bit; the gap counted in the health readout
     * (one sample_time), the other sensors' not */
    const double bad[3] = {NAN, INFINITY, -INFINITY};
    for (int i = 0; i < 3; ++i)
        for (int v = 0; v < 3; ++v) {
            double gg[3], aa[3], mm[3];
            const double nan_row[3] = {NAN, NAN, NAN};
            sample(50, gg, aa, mm);
            gg[i] = bad[v];
            bingham_ahrs *c1 = NULL, *c2 = NULL;
            CHECK_OK(bingham_ahrs_clone(a, &c1));
            CHECK_OK(bingham_ahrs_clone(a, &c2));
            if (!c1 || !c2) return;
            CHECK_OK(bingham_ahrs_update(c1, gg, aa, mm));
            CHECK_OK(bingham_ahrs_update(c2, nan_row, aa, mm));
            astate t = asnap(c1);
            CHECK(same_state(t, asnap(c2)));
            CHECK(all_finite(t.q, 4) && all_finite(t.m, 16) && all_finite(t.z, 4) && all_finite(t.ocov, 9));
            bingham_ahrs_health_report h;
            memset(&h, 0, sizeof h);
            CHECK_OK(bingham_ahrs_health(c1, &h));
            CHECK(h.gyr_missing_time == 0.01 && h.acc_missing_time == 0.0 && h.mag_missing_time == 0.0);
            bingham_ahrs_free(c1);
            bingham_ahrs_free(c2);
        }
    CHECK(same_state(s, asnap(a)));
    /* a finite gyroscope sample turning by more than 1e6 rad in one sample (|gyr| * 0.01 s):
     * not a rate, refused with the AHRS unchanged (a clone taken before, fed the same next
     * sample, stays identical: no hidden state changed either) */
    {
        const double huge_g[4][3] = {{2e8, 0.0, 0.0}, {0.0, -1e12, 0.0}, {1e150, 1e150, -1e150}, {-5e9, 5e9, 0.0}};
        bingham_ahrs *c = NULL;
        CHECK_OK(bingham_ahrs_clone(a, &c));
        if (!c) return;
        for (int k = 0; k < 4; ++k) {
            double gg[3], aa[3], mm[3];
            sample(50, gg, aa, mm);
            CHECK_STATUS(bingham_ahrs_update(a, huge_g[k], aa, mm), BINGHAM_ERR_INVALID_ARGUMENT);
            check_msg(fn, "gyroscope");
            CHECK(same_state(s, asnap(a)));
        }
        double gg[3], aa[3], mm[3];
        sample(50, gg, aa, mm);
        CHECK_OK(bingham_ahrs_update(a, gg, aa, mm));
        CHECK_OK(bingham_ahrs_update(c, gg, aa, mm));
        CHECK(same_state(asnap(a), asnap(c)));
        bingham_ahrs_free(c);
        s = asnap(a);
    }
    /* NaN / Inf in an accelerometer or magnetometer entry: "no sample" of that sensor, accepted
     * (on clones); a non-finite field is the same as mag = NULL, bit for bit */
    for (int which = 1; which < 3; ++which)
        for (int i = 0; i < 3; ++i)
            for (int v = 0; v < 3; ++v) {
                double gg[3], aa[3], mm[3];
                sample(50, gg, aa, mm);
                (which == 1 ? aa : mm)[i] = bad[v];
                bingham_ahrs *c1 = NULL, *c2 = NULL;
                CHECK_OK(bingham_ahrs_clone(a, &c1));
                CHECK_OK(bingham_ahrs_clone(a, &c2));
                if (!c1 || !c2) return;
                CHECK_OK(bingham_ahrs_update(c1, gg, aa, mm));
                astate t = asnap(c1);
                CHECK(all_finite(t.q, 4) && all_finite(t.m, 16) && all_finite(t.z, 4) && all_finite(t.cov, 9));
                if (which == 2) {
                    CHECK_OK(bingham_ahrs_update(c2, gg, aa, NULL));
                    CHECK(same_state(t, asnap(c2)));
                }
                bingham_ahrs_free(c1);
                bingham_ahrs_free(c2);
            }
    CHECK(same_state(s, asnap(a)));
    /* mag = NULL accepted; a zero field, free fall and a huge sample are not errors */
    sample(50, g, acc, mag);
    CHECK_OK(bingham_ahrs_update(a, g, acc, NULL));
    CHECK_OK(bingham_ahrs_update(a, g, acc, zero));
    CHECK_OK(bingham_ahrs_update(a, g, zero, mag));
    double huge[3] = {1e300, -1e300, 1e300};
    int st = (int)bingham_ahrs_update(a, g, acc, huge);
    CHECK(st == BINGHAM_OK || st == BINGHAM_ERR_INVALID_ARGUMENT);
    s = asnap(a);
    CHECK(all_finite(s.q, 4) && all_finite(s.m, 16) && all_finite(s.z, 4) && all_finite(s.bias, 3));
    /* getters: NULLs, outputs untouched */
    double buf[16];
    fill(buf, sizeof buf);
    CHECK_STATUS(bingham_ahrs_quaternion(NULL, buf), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_quaternion", "a");
    CHECK_STATUS(bingham_ahrs_quaternion(a, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_quaternion", "q");
    CHECK_STATUS(bingham_ahrs_state(NULL, buf, buf), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_state", "a");
    CHECK_STATUS(bingham_ahrs_state(a, NULL, buf), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_state", "m");
    CHECK_STATUS(bingham_ahrs_state(a, buf, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_state", "z");
    CHECK_STATUS(bingham_ahrs_angular_spread(NULL, buf), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_angular_spread", "a");
    CHECK_STATUS(bingham_ahrs_angular_spread(a, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_angular_spread", "spread");
    CHECK_STATUS(bingham_ahrs_gyro_bias(NULL, buf), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_gyro_bias", "a");
    CHECK_STATUS(bingham_ahrs_gyro_bias(a, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_gyro_bias", "bias");
    CHECK_STATUS(bingham_ahrs_gyro_bias_covariance(NULL, buf), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_gyro_bias_covariance", "a");
    CHECK_STATUS(bingham_ahrs_gyro_bias_covariance(a, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_gyro_bias_covariance", "cov");
    CHECK_STATUS(bingham_ahrs_gyro_scale(NULL, buf), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_gyro_scale", "a");
    CHECK_STATUS(bingham_ahrs_gyro_scale(a, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_gyro_scale", "scale");
    CHECK(untouched(buf, sizeof buf));
    /* set_state: NULLs, NaN and a non-orthogonal M refused with the AHRS unchanged; a valid
     * state is taken (its mode becomes the estimate) */
    {
        astate before = asnap(a);
        double m[16] = {0}, z[4] = {-50.0, -50.0, -50.0, 0.0}, q[4];
        for (int i = 0; i < 4; ++i) m[i * 4 + (3 - i)] = 1.0; /* anti-diagonal: mode (1,0,0,0) */
        CHECK_STATUS(bingham_ahrs_set_state(NULL, m, z), BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg("bingham_ahrs_set_state", "a");
        CHECK_STATUS(bingham_ahrs_set_state(a, NULL, z), BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg("bingham_ahrs_set_state", "m");
        CHECK_STATUS(bingham_ahrs_set_state(a, m, NULL), BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg("bingham_ahrs_set_state", "z");
        z[1] = NAN;
        CHECK_STATUS(bingham_ahrs_set_state(a, m, z), BINGHAM_ERR_INVALID_ARGUMENT);
        z[1] = -50.0;
        m[0] = 0.1;
        CHECK_STATUS(bingham_ahrs_set_state(a, m, z), BINGHAM_ERR_INVALID_ARGUMENT);
        m[0] = 0.0;
        CHECK(same_state(before, asnap(a)));
        bingham_ahrs *t = NULL;
        CHECK_OK(bingham_ahrs_clone(a, &t));
        if (t) {
            CHECK_OK(bingham_ahrs_set_state(t, m, z));
            CHECK_OK(bingham_ahrs_quaternion(t, q));
            CHECK(fabs(q[0] - 1.0) < 1e-12 && fabs(q[1]) < 1e-12 && fabs(q[2]) < 1e-12 && fabs(q[3]) < 1e-12);
            bingham_ahrs_free(t);
        }
    }
    /* clone: NULLs; then identical evolution */
    bingham_ahrs *c = (bingham_ahrs *)no_access();
    CHECK_STATUS(bingham_ahrs_clone(NULL, &c), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_clone", "a");
    CHECK_STATUS(bingham_ahrs_clone(a, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg("bingham_ahrs_clone", "out");
    CHECK(c == (bingham_ahrs *)no_access());
    c = NULL;
    CHECK_OK(bingham_ahrs_clone(a, &c));
    if (c) {
        CHECK(same_state(asnap(a), asnap(c)));
        for (int k = 60; k < 300; ++k) {
            sample(k, g, acc, mag);
            g[0] += 0.5 * sin(0.05 * k); /* some motion */
            CHECK_OK(bingham_ahrs_update(a, g, acc, k % 3 ? mag : NULL));
            CHECK_OK(bingham_ahrs_update(c, g, acc, k % 3 ? mag : NULL));
        }
        CHECK(same_state(asnap(a), asnap(c)));
        /* independent: updating the clone does not touch the original */
        astate sa = asnap(a);
        CHECK_OK(bingham_ahrs_update(c, g, acc, mag));
        CHECK(same_state(sa, asnap(a)));
        bingham_ahrs_free(c);
    }
    bingham_ahrs_free(a);
}

static void test_ahrs_batch(void) {
    enum { N = 10 };
    double g[3 * N], acc[3 * N], mag[3 * N], quat[4 * N], spread[N];
    for (int k = 0; k < N; ++k) sample(k, g + 3 * k, acc + 3 * k, mag + 3 * k);
    const char *fns[2] = {"bingham_ahrs_update_batch", "bingham_ahrs_update_batch_spread"};
    for (int variant = 0; variant < 2; ++variant)
        for (int which = 0; which < 4; ++which) {
            const char *fn = fns[variant];
            bingham_ahrs *a = new_ahrs(0.01), *ref = new_ahrs(0.01);
            if (!a || !ref) return;
            /* a NaN in sample 5 (which 0..2): "no sample" of that sensor (the gyroscope's a gap
             * the AHRS carries the orientation through), the batch runs on; a gyroscope entry
             * turning by more than 1e6 rad in the sample (which 3) stops the batch there */
            double *arr = which == 0 || which == 3 ? g : which == 1 ? acc : mag;
            double saved = arr[3 * 5 + 1];
            arr[3 * 5 + 1] = which == 3 ? 1e12 : NAN;
            fill(quat, sizeof quat);
            fill(spread, sizeof spread);
            int st = variant ? (int)bingham_ahrs_update_batch_spread(a, N, g, acc, mag, quat, spread)
                             : (int)bingham_ahrs_update_batch(a, N, g, acc, mag, quat);
            const int done = which == 3 ? 5 : N;
            if (which == 3) {
                CHECK_STATUS(st, BINGHAM_ERR_INVALID_ARGUMENT);
                check_msg(fn, "sample 5");
            } else {
                CHECK_OK(st);
            }
            /* rows 0..done-1 written, equal to single updates (with the same NaN row); the rest
             * untouched */
            for (int k = 0; k < done; ++k) {
                double q[4], sp[4];
                CHECK_OK(bingham_ahrs_update(ref, g + 3 * k, acc + 3 * k, mag + 3 * k));
                CHECK_OK(bingham_ahrs_quaternion(ref, q));
                CHECK(memcmp(q, quat + 4 * k, sizeof q) == 0);
                if (variant) {
                    CHECK_OK(bingham_ahrs_angular_spread(ref, sp));
                    CHECK(spread[k] == sp[3]);
                }
            }
            arr[3 * 5 + 1] = saved;
            CHECK(untouched(quat + 4 * done, 4 * (size_t)(N - done) * sizeof(double)));
            CHECK(untouched(variant ? spread + done : spread, (size_t)(variant ? N - done : N) * sizeof(double)));
            /* the AHRS holds the state after the last processed sample */
            CHECK(same_state(asnap(a), asnap(ref)));
            bingham_ahrs_free(a);
            bingham_ahrs_free(ref);
        }
    /* a first sample without an accelerometer: refused at "sample 0", nothing written */
    {
        bingham_ahrs *a = new_ahrs(0.01);
        if (!a) return;
        astate s0 = asnap(a);
        double saved = acc[2];
        acc[2] = NAN;
        fill(quat, sizeof quat);
        CHECK_STATUS(bingham_ahrs_update_batch(a, N, g, acc, mag, quat), BINGHAM_ERR_INVALID_ARGUMENT);
        check_msg("bingham_ahrs_update_batch", "sample 0");
        acc[2] = saved;
        CHECK(untouched(quat, sizeof quat) && same_state(s0, asnap(a)));
        bingham_ahrs_free(a);
    }
    /* full batch = single updates; mag and spread NULL accepted */
    for (int use_mag = 0; use_mag < 2; ++use_mag) {
        bingham_ahrs *a = new_ahrs(0.01), *ref = new_ahrs(0.01);
        if (!a || !ref) return;
        CHECK_OK(bingham_ahrs_update_batch_spread(a, N, g, acc, use_mag ? mag : NULL, quat, NULL));
        for (int k = 0; k < N; ++k) CHECK_OK(bingham_ahrs_update(ref, g + 3 * k, acc + 3 * k, use_mag ? mag + 3 * k : NULL));
        CHECK(same_state(asnap(a), asnap(ref)));
        for (int k = 0; k < N; ++k) {
            double *q = quat + 4 * k;
            CHECK(q[0] >= 0.0 && fabs(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] - 1) < 1e-12);
        }
        /* n = 0: nothing happens */
        astate s = asnap(a);
        fill(quat, sizeof quat);
        CHECK_OK(bingham_ahrs_update_batch(a, 0, g, acc, mag, quat));
        CHECK(untouched(quat, sizeof quat) && same_state(s, asnap(a)));
        /* NULLs */
        const char *fn = "bingham_ahrs_update_batch";
        CHECK_STATUS(bingham_ahrs_update_batch(NULL, N, g, acc, mag, quat), BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "a");
        CHECK_STATUS(bingham_ahrs_update_batch(a, N, NULL, acc, mag, quat), BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "gyr");
        CHECK_STATUS(bingham_ahrs_update_batch(a, N, g, NULL, mag, quat), BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "acc");
        CHECK_STATUS(bingham_ahrs_update_batch(a, N, g, acc, mag, NULL), BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "quat");
        CHECK_STATUS(bingham_ahrs_update_batch_spread(a, N, g, acc, mag, NULL, spread), BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg("bingham_ahrs_update_batch_spread", "quat");
        /* n * 4 overflowing: refused before any access */
        CHECK_STATUS(bingham_ahrs_update_batch(a, (size_t)-1 / 2, no_access(), no_access(), NULL, no_access()),
                     BINGHAM_ERR_INVALID_DIMENSION);
        check_msg(fn, NULL);
        CHECK(untouched(quat, sizeof quat) && same_state(s, asnap(a)));
        bingham_ahrs_free(a);
        bingham_ahrs_free(ref);
    }
}

/* ---- the health readout ------------------------------------------------------------------------ */

static void hsnap(const bingham_ahrs *a, bingham_ahrs_health_report *h) {
    memset(h, 0, sizeof *h);
    CHECK_OK(bingham_ahrs_health(a, h));
}

/* Every field finite, the score the largest of the three averages, the rejected fraction in
 * [0, 1], the innovations non-negative where they are angles. */
static void check_health_consistent(const bingham_ahrs_health_report *h) {
    const double v[11] = {h->score,           h->gravity_score,      h->tilt_score,   h->heading_score,
                          h->tilt_innovation, h->heading_innovation, h->mag_rejected, h->mag_dip,
                          h->gyr_missing_time, h->acc_missing_time,  h->mag_missing_time};
    CHECK(all_finite(v, 11));
    CHECK(h->gyr_missing_time >= 0.0 && h->acc_missing_time >= 0.0 && h->mag_missing_time >= 0.0);
    CHECK(h->score == fmax(h->gravity_score, fmax(h->tilt_score, h->heading_score)));
    CHECK(h->gravity_score >= 0.0 && h->tilt_score >= 0.0 && h->heading_score >= 0.0);
    CHECK(h->tilt_innovation >= 0.0 && h->tilt_innovation <= PI);
    CHECK(h->mag_rejected >= 0.0 && h->mag_rejected <= 1.0);
    CHECK(h->has_mag_reference == 0 || h->has_mag_reference == 1);
}

static void test_ahrs_health(void) {
    const char *fn = "bingham_ahrs_health";
    /* the field of sample(): world (0, 20, -40) in ENU, 40 down and 20 north: a dip of
     * atan(40 / 20) below the horizon (positive) */
    const double dip = atan2(40.0, 20.0);
    bingham_ahrs_health_report h;
    bingham_ahrs *a = new_ahrs(0.01);
    if (!a) return;
    /* before the first sample: all zero, no reference */
    fill(&h, sizeof h);
    CHECK_OK(bingham_ahrs_health(a, &h));
    CHECK(h.score == 0.0 && h.gravity_score == 0.0 && h.tilt_score == 0.0 && h.heading_score == 0.0);
    CHECK(h.tilt_innovation == 0.0 && h.heading_innovation == 0.0 && h.mag_rejected == 0.0 && h.mag_dip == 0.0);
    CHECK(h.has_mag_reference == 0);
    CHECK(h.gyr_missing_time == 0.0 && h.acc_missing_time == 0.0 && h.mag_missing_time == 0.0);
    /* NULLs: refused, the output untouched, the AHRS unchanged */
    astate s0 = asnap(a);
    fill(&h, sizeof h);
    CHECK_STATUS(bingham_ahrs_health(NULL, &h), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fn, "a");
    CHECK(untouched(&h, sizeof h));
    CHECK_STATUS(bingham_ahrs_health(a, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fn, "out");
    CHECK(same_state(s0, asnap(a)));

    /* 5 s of the slow turn with a magnetometer */
    double g[3], acc[3], mag[3];
    for (int k = 0; k < 500; ++k) {
        sample(k, g, acc, mag);
        CHECK_OK(bingham_ahrs_update(a, g, acc, mag));
    }
    astate s1 = asnap(a);
    hsnap(a, &h);
    check_health_consistent(&h);
    CHECK(same_state(s1, asnap(a))); /* a readout does not change the AHRS */
    CHECK(h.has_mag_reference == 1);
    if (fabs(h.mag_dip - dip) > 0.01) fprintf(stderr, "    mag_dip %.6f, field's dip %.6f\n", h.mag_dip, dip);
    CHECK(h.mag_dip > 0.0 && fabs(h.mag_dip - dip) <= 0.01);
    CHECK(h.tilt_score > 0.0);      /* corrections have happened */
    CHECK(h.heading_score > 0.0);   /* ... with a heading observation */
    CHECK(h.mag_rejected <= 0.5);   /* a clean, constant field: mostly used */
    /* correct input: below the documented threshold */
    if (!(h.score < BINGHAM_AHRS_HEALTH_THRESHOLD)) fprintf(stderr, "    score %g\n", h.score);
    CHECK(h.score < BINGHAM_AHRS_HEALTH_THRESHOLD);
    /* a second readout: identical */
    bingham_ahrs_health_report h2;
    hsnap(a, &h2);
    CHECK(memcmp(&h, &h2, sizeof h) == 0);
    /* errors after samples: output untouched */
    fill(&h2, sizeof h2);
    CHECK_STATUS(bingham_ahrs_health(NULL, &h2), BINGHAM_ERR_NULL_ARGUMENT);
    CHECK(untouched(&h2, sizeof h2));
    bingham_ahrs_free(a);

    /* without a magnetometer: no reference, no heading, nothing rejected */
    a = new_ahrs(0.01);
    if (!a) return;
    for (int k = 0; k < 500; ++k) {
        sample(k, g, acc, mag);
        CHECK_OK(bingham_ahrs_update(a, g, acc, NULL));
    }
    hsnap(a, &h);
    check_health_consistent(&h);
    CHECK(h.has_mag_reference == 0 && h.mag_dip == 0.0 && h.heading_score == 0.0 && h.heading_innovation == 0.0);
    CHECK(h.mag_rejected == 0.0 && h.tilt_score > 0.0 && h.score == h.tilt_score);
    bingham_ahrs_free(a);

    /* a flipped accelerometer (gravity instead of specific force): the dip changes sign */
    a = new_ahrs(0.01);
    if (!a) return;
    for (int k = 0; k < 500; ++k) {
        sample(k, g, acc, mag);
        for (int i = 0; i < 3; ++i) acc[i] = -acc[i];
        CHECK_OK(bingham_ahrs_update(a, g, acc, mag));
    }
    hsnap(a, &h);
    check_health_consistent(&h);
    if (fabs(h.mag_dip + dip) > 0.01) fprintf(stderr, "    flipped: mag_dip %.6f\n", h.mag_dip);
    CHECK(h.has_mag_reference == 1 && h.mag_dip < 0.0 && fabs(h.mag_dip + dip) <= 0.01);
    bingham_ahrs_free(a);
}

static void test_ahrs_batch_health(void) {
    const char *fn = "bingham_ahrs_update_batch_health";
    enum { N = 400 };
    static double g[3 * N], acc[3 * N], mag[3 * N], quat[4 * N], spread[N], health[N];
    for (int k = 0; k < N; ++k) {
        sample(k, g + 3 * k, acc + 3 * k, mag + 3 * k);
        g[3 * k] += 0.5 * sin(0.05 * k); /* some motion */
        if (k % 7 == 3) mag[3 * k + 1] = NAN; /* no magnetometer sample */
        if (k % 50 == 17 || (k >= 230 && k < 236)) g[3 * k + 2] = NAN; /* gyroscope gaps */
    }
    /* from a fresh AHRS (the first samples included) and from a clone of one 200 samples in:
     * every row equal to single updates and the readout after them */
    for (int from_clone = 0; from_clone < 2; ++from_clone)
        for (int outputs = 0; outputs < 4; ++outputs) { /* bit 0: spread, bit 1: health */
            bingham_ahrs *a = new_ahrs(0.01), *ref = NULL;
            if (!a) return;
            if (from_clone)
                for (int k = 0; k < 200; ++k) CHECK_OK(bingham_ahrs_update(a, g + 3 * k, acc + 3 * k, mag + 3 * k));
            CHECK_OK(bingham_ahrs_clone(a, &ref));
            if (!ref) return;
            const int n = from_clone ? N - 200 : N, off = from_clone ? 200 : 0;
            double *sp_out = outputs & 1 ? spread : NULL, *h_out = outputs & 2 ? health : NULL;
            fill(quat, sizeof quat);
            fill(spread, sizeof spread);
            fill(health, sizeof health);
            CHECK_OK(bingham_ahrs_update_batch_health(a, (size_t)n, g + 3 * off, acc + 3 * off, mag + 3 * off, quat,
                                                      sp_out, h_out));
            int q_same = 1, sp_same = 1, h_same = 1, h_zero_first = 1;
            for (int k = 0; k < n; ++k) {
                double q[4], sp[4];
                bingham_ahrs_health_report r;
                CHECK_OK(bingham_ahrs_update(ref, g + 3 * (off + k), acc + 3 * (off + k), mag + 3 * (off + k)));
                CHECK_OK(bingham_ahrs_quaternion(ref, q));
                CHECK_OK(bingham_ahrs_angular_spread(ref, sp));
                CHECK_OK(bingham_ahrs_health(ref, &r));
                q_same &= memcmp(q, quat + 4 * k, sizeof q) == 0;
                if (sp_out) sp_same &= spread[k] == sp[3];
                if (h_out) h_same &= memcmp(&health[k], &r.score, sizeof(double)) == 0;
                if (!from_clone && k == 0) h_zero_first = r.score == 0.0; /* no correction yet */
            }
            CHECK(q_same && sp_same && h_same && h_zero_first);
            if (!sp_out) CHECK(untouched(spread, sizeof spread));
            if (!h_out) CHECK(untouched(health, sizeof health));
            if (h_out) CHECK(all_finite(health, (size_t)n) && health[n - 1] > 0.0);
            CHECK(untouched(quat + 4 * n, 4 * (size_t)(N - n) * sizeof(double)));
            /* the AHRS holds the state and the readout after the last sample */
            bingham_ahrs_health_report ha, hr;
            hsnap(a, &ha);
            hsnap(ref, &hr);
            CHECK(same_state(asnap(a), asnap(ref)) && memcmp(&ha, &hr, sizeof ha) == 0);
            if (h_out) CHECK(health[n - 1] == ha.score);
            bingham_ahrs_free(a);
            bingham_ahrs_free(ref);
        }
    /* mag = NULL: equal to single updates without a magnetometer */
    {
        bingham_ahrs *a = new_ahrs(0.01), *ref = new_ahrs(0.01);
        if (!a || !ref) return;
        CHECK_OK(bingham_ahrs_update_batch_health(a, 100, g, acc, NULL, quat, NULL, health));
        int h_same = 1;
        for (int k = 0; k < 100; ++k) {
            bingham_ahrs_health_report r;
            CHECK_OK(bingham_ahrs_update(ref, g + 3 * k, acc + 3 * k, NULL));
            CHECK_OK(bingham_ahrs_health(ref, &r));
            h_same &= health[k] == r.score && r.has_mag_reference == 0;
        }
        CHECK(h_same && same_state(asnap(a), asnap(ref)));
        bingham_ahrs_free(a);
        bingham_ahrs_free(ref);
    }
    /* a gyroscope entry turning by more than 1e6 rad in sample 5: refused there, rows 0..4
     * written, the rest untouched */
    {
        bingham_ahrs *a = new_ahrs(0.01), *ref = new_ahrs(0.01);
        if (!a || !ref) return;
        double saved = g[3 * 5 + 2];
        g[3 * 5 + 2] = -3e8;
        fill(quat, sizeof quat);
        fill(spread, sizeof spread);
        fill(health, sizeof health);
        CHECK_STATUS(bingham_ahrs_update_batch_health(a, 10, g, acc, mag, quat, spread, health),
                     BINGHAM_ERR_INVALID_ARGUMENT);
        check_msg(fn, "sample 5");
        g[3 * 5 + 2] = saved;
        int rows_same = 1;
        for (int k = 0; k < 5; ++k) {
            double q[4];
            bingham_ahrs_health_report r;
            CHECK_OK(bingham_ahrs_update(ref, g + 3 * k, acc + 3 * k, mag + 3 * k));
            CHECK_OK(bingham_ahrs_quaternion(ref, q));
            CHECK_OK(bingham_ahrs_health(ref, &r));
            rows_same &= memcmp(q, quat + 4 * k, sizeof q) == 0 && health[k] == r.score;
        }
        CHECK(rows_same);
        CHECK(untouched(quat + 4 * 5, sizeof quat - 4 * 5 * sizeof(double)));
        CHECK(untouched(spread + 5, sizeof spread - 5 * sizeof(double)));
        CHECK(untouched(health + 5, sizeof health - 5 * sizeof(double)));
        CHECK(same_state(asnap(a), asnap(ref)));
        bingham_ahrs_free(a);
        bingham_ahrs_free(ref);
    }
    /* NULLs: refused, nothing written, the AHRS unchanged */
    {
        bingham_ahrs *a = new_ahrs(0.01);
        if (!a) return;
        astate s = asnap(a);
        fill(quat, sizeof quat);
        fill(spread, sizeof spread);
        fill(health, sizeof health);
        CHECK_STATUS(bingham_ahrs_update_batch_health(NULL, 10, g, acc, mag, quat, spread, health),
                     BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "a");
        CHECK_STATUS(bingham_ahrs_update_batch_health(a, 10, NULL, acc, mag, quat, spread, health),
                     BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "gyr");
        CHECK_STATUS(bingham_ahrs_update_batch_health(a, 10, g, NULL, mag, quat, spread, health),
                     BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "acc");
        CHECK_STATUS(bingham_ahrs_update_batch_health(a, 10, g, acc, mag, NULL, spread, health),
                     BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "quat");
        CHECK(untouched(quat, sizeof quat) && untouched(spread, sizeof spread) && untouched(health, sizeof health));
        CHECK(same_state(s, asnap(a)));
        bingham_ahrs_free(a);
    }
}

/* ---- the gyroscope bias's uncertainty ------------------------------------------------------------ */

static void test_ahrs_bias_uncertainty(void) {
    const char *fn = "bingham_ahrs_gyro_bias_covariance";
    bingham_ahrs_params p, q;
    CHECK_OK(bingham_ahrs_params_default(0.01, &p));
    CHECK(fabs(p.bias_std - 0.5 * PI / 180.0) <= 1e-15); /* 0.5 deg/s */
    CHECK(p.gyro_scale_noise >= 0.0 && isfinite(p.gyro_scale_noise));
    /* invalid values refused by bingham_ahrs_new, the message naming the field */
    bingham_ahrs *a = (bingham_ahrs *)no_access();
    const double bad_std[6] = {NAN, -1.0, -1e-300, 0.0, -0.0, INFINITY};
    for (int k = 0; k < 6; ++k) {
        q = p;
        q.bias_std = bad_std[k];
        CHECK_STATUS(bingham_ahrs_new(&q, &a), BINGHAM_ERR_INVALID_ARGUMENT);
        check_msg("bingham_ahrs_new", "bias_std");
        CHECK(a == (bingham_ahrs *)no_access());
    }
    const double bad_scale[4] = {NAN, -1.0, -1e-300, INFINITY};
    for (int k = 0; k < 4; ++k) {
        q = p;
        q.gyro_scale_noise = bad_scale[k];
        CHECK_STATUS(bingham_ahrs_new(&q, &a), BINGHAM_ERR_INVALID_ARGUMENT);
        check_msg("bingham_ahrs_new", "gyro_scale_noise");
        CHECK(a == (bingham_ahrs *)no_access());
    }
    /* gyro_scale_std: 0 to 0.05 */
    CHECK(p.gyro_scale_std >= 0.0 && p.gyro_scale_std <= 0.05);
    const double bad_scale_std[4] = {NAN, -1e-3, 0.06, INFINITY};
    for (int k = 0; k < 4; ++k) {
        q = p;
        q.gyro_scale_std = bad_scale_std[k];
        CHECK_STATUS(bingham_ahrs_new(&q, &a), BINGHAM_ERR_INVALID_ARGUMENT);
        check_msg("bingham_ahrs_new", "gyro_scale_std");
        CHECK(a == (bingham_ahrs *)no_access());
    }
    /* gyro_scale_noise = 0 is valid (no rate-proportional noise) */
    q = p;
    q.gyro_scale_noise = 0.0;
    a = NULL;
    CHECK_OK(bingham_ahrs_new(&q, &a));
    bingham_ahrs_free(a);
    /* gyro_scale_std = 0 is valid (the scale not estimated) */
    q = p;
    q.gyro_scale_std = 0.0;
    a = NULL;
    CHECK_OK(bingham_ahrs_new(&q, &a));
    bingham_ahrs_free(a);

    /* the covariance: NULLs (output untouched), bias_std^2 I on creation, for the default and
     * for another bias_std */
    for (int variant = 0; variant < 2; ++variant) {
        q = p;
        if (variant) q.bias_std = 0.02;
        a = NULL;
        CHECK_OK(bingham_ahrs_new(&q, &a));
        if (!a) return;
        double cov[9];
        fill(cov, sizeof cov);
        CHECK_STATUS(bingham_ahrs_gyro_bias_covariance(NULL, cov), BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "a");
        CHECK_STATUS(bingham_ahrs_gyro_bias_covariance(a, NULL), BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "cov");
        CHECK(untouched(cov, sizeof cov));
        CHECK_OK(bingham_ahrs_gyro_bias_covariance(a, cov));
        for (int i = 0; i < 9; ++i) CHECK(cov[i] == (i % 4 == 0 ? q.bias_std * q.bias_std : 0.0));
        bingham_ahrs_free(a);
    }

    /* after 30 s of a slow turn about the vertical with gravity and a field: the corrections
     * have taught the bias: symmetric, positive diagonal below bias_std^2 */
    a = new_ahrs(0.01);
    if (!a) return;
    for (int k = 0; k < 3000; ++k) {
        double g[3], acc[3], mag[3];
        sample(k, g, acc, mag);
        CHECK_OK(bingham_ahrs_update(a, g, acc, mag));
    }
    double cov[9], var0 = p.bias_std * p.bias_std;
    CHECK_OK(bingham_ahrs_gyro_bias_covariance(a, cov));
    CHECK(all_finite(cov, 9));
    for (int i = 0; i < 3; ++i) {
        if (!(cov[4 * i] > 0.0 && cov[4 * i] < var0))
            fprintf(stderr, "    cov[%d][%d] = %g, bias_std^2 = %g\n", i, i, cov[4 * i], var0);
        CHECK(cov[4 * i] > 0.0 && cov[4 * i] < var0);
        for (int j = 0; j < 3; ++j) CHECK(fabs(cov[3 * i + j] - cov[3 * j + i]) <= 1e-12 * var0);
    }
    /* NaN gyroscope, accelerometer and magnetometer rows in the middle of the stream: each a
     * missing sample of that sensor, accepted; the health readout's missing time of that sensor
     * grows by sample_time per missing row and is 0 again after a usable sample */
    {
        double g[3], acc[3], mag[3];
        int k = 3000;
        for (int which = 0; which < 3; ++which) {
            for (int r = 1; r <= 3; ++r, ++k) {
                sample(k, g, acc, mag);
                if (which == 0)
                    g[r - 1] = NAN;
                else if (which == 1)
                    acc[r - 1] = NAN;
                else
                    mag[r - 1] = NAN;
                CHECK_OK(bingham_ahrs_update(a, g, acc, mag));
                bingham_ahrs_health_report h;
                hsnap(a, &h);
                const double missing[3] = {h.gyr_missing_time, h.acc_missing_time, h.mag_missing_time};
                for (int i = 0; i < 3; ++i) {
                    if (i == which) CHECK_CLOSE(missing[i], 0.01 * r, 1e-15);
                    else CHECK(missing[i] == 0.0);
                }
            }
            sample(k++, g, acc, mag);
            CHECK_OK(bingham_ahrs_update(a, g, acc, mag));
            bingham_ahrs_health_report h;
            hsnap(a, &h);
            CHECK(h.gyr_missing_time == 0.0 && h.acc_missing_time == 0.0 && h.mag_missing_time == 0.0);
        }
        astate s1 = asnap(a);
        CHECK(all_finite(s1.q, 4) && all_finite(s1.cov, 9) && all_finite(s1.ocov, 9));
    }
    bingham_ahrs_free(a);
}

/* ---- the gyroscope's scale error ---------------------------------------------------------------- */

/* An upright sensor at 100 Hz: 10 s at rest, then 120 s turning about the vertical at 1 rad/s,
 * the direction reversed every 5 s, with a gyroscope that reads (1 + s_z) times the rate about
 * its z axis. The truth is known: the heading corrections show a drift s_z·ω that flips sign
 * with the rate, which a bias cannot explain (the rest fixed it, and it does not flip). Returns
 * the scale estimate; `std` the prior (gyro_scale_std). */
static void spin_scale(double s_z, double std, double est[3]) {
    bingham_ahrs_params p;
    bingham_ahrs *a = NULL;
    const double dt = 0.01, dip = 60.0 * PI / 180.0;
    double yaw = 0.0;
    CHECK_OK(bingham_ahrs_params_default(dt, &p));
    p.gyro_scale_std = std;
    CHECK_OK(bingham_ahrs_new(&p, &a));
    for (int k = 0; k < 13000; k++) {
        double t = dt * k, w = 0.0;
        if (t >= 10.0) w = ((int)((t - 10.0) / 5.0) % 2 == 0) ? 1.0 : -1.0;
        double g[3] = {0.0, 0.0, (1.0 + s_z) * w};
        double acc[3] = {0.0, 0.0, 9.81};
        /* world field (0, cos dip, -sin dip)·50 µT (ENU) seen by a sensor turned by yaw about z */
        double mag[3] = {50.0 * cos(dip) * sin(yaw), 50.0 * cos(dip) * cos(yaw), -50.0 * sin(dip)};
        CHECK_OK(bingham_ahrs_update(a, g, acc, mag));
        yaw += w * dt;
    }
    CHECK_OK(bingham_ahrs_gyro_scale(a, est));
    bingham_ahrs_free(a);
}

static void test_ahrs_gyro_scale(void) {
    double est[3], fresh[3];
    /* creation: zero */
    bingham_ahrs *a = new_ahrs(0.01);
    CHECK_OK(bingham_ahrs_gyro_scale(a, fresh));
    CHECK(fresh[0] == 0.0 && fresh[1] == 0.0 && fresh[2] == 0.0);
    bingham_ahrs_free(a);
    /* a 1 % scale error with a prior of its size: learned about z to within a third, nothing
     * about the axes the rotation never excites */
    spin_scale(0.01, 0.01, est);
    if (!(fabs(est[2] - 0.01) < 0.0033 && fabs(est[0]) < 1e-3 && fabs(est[1]) < 1e-3)) {
        fprintf(stderr, "gyro scale estimate (%g, %g, %g) for (0, 0, 0.01)\n", est[0], est[1], est[2]);
        CHECK(0);
    }
    /* gyro_scale_std = 0: not estimated, exactly zero */
    spin_scale(0.01, 0.0, est);
    CHECK(est[0] == 0.0 && est[1] == 0.0 && est[2] == 0.0);
}

/* ---- the latencies ---------------------------------------------------------------------------- */

static void qmul(const double *a, const double *b, double *out) {
    double r[4] = {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
                   a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
                   a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
                   a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
    memcpy(out, r, sizeof r);
}

/* R(q)^T v: a world vector in the sensor frame of q. */
static void to_sensor(const double *q, const double *v, double *out) {
    double c[4] = {q[0], -q[1], -q[2], -q[3]}, p[4] = {0.0, v[0], v[1], v[2]}, t[4];
    qmul(c, p, t);
    qmul(t, q, t);
    out[0] = t[1], out[1] = t[2], out[2] = t[3];
}

static void test_ahrs_latency(void) {
    const char *fn = "bingham_ahrs_mag_latency_estimate";
    bingham_ahrs_params p, q;
    CHECK_OK(bingham_ahrs_params_default(0.01, &p));
    /* default: the magnetometer's online estimate compensated, no accelerometer latency */
    CHECK(p.mag_latency == BINGHAM_AHRS_LATENCY_ESTIMATE && p.acc_latency == 0.0);
    const double bad[5] = {-1e-9, BINGHAM_AHRS_MAX_LATENCY * 1.000001, 11.0, NAN, INFINITY};
    bingham_ahrs *a = (bingham_ahrs *)no_access();
    for (int k = 0; k < 5; ++k) {
        q = p;
        q.mag_latency = bad[k];
        CHECK_STATUS(bingham_ahrs_new(&q, &a), BINGHAM_ERR_INVALID_ARGUMENT);
        check_msg("bingham_ahrs_new", "mag_latency");
        q = p;
        q.acc_latency = bad[k];
        CHECK_STATUS(bingham_ahrs_new(&q, &a), BINGHAM_ERR_INVALID_ARGUMENT);
        check_msg("bingham_ahrs_new", "acc_latency");
        CHECK(a == (bingham_ahrs *)no_access());
    }
    q = p;
    q.mag_latency = 0.02, q.acc_latency = BINGHAM_AHRS_MAX_LATENCY;
    a = NULL;
    CHECK_OK(bingham_ahrs_new(&q, &a));
    bingham_ahrs_free(a);

    a = new_ahrs(0.01);
    if (!a) return;
    double l;
    fill(&l, sizeof l);
    CHECK_STATUS(bingham_ahrs_mag_latency_estimate(NULL, &l), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fn, "a");
    CHECK_STATUS(bingham_ahrs_mag_latency_estimate(a, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fn, "latency");
    CHECK_STATUS(bingham_ahrs_mag_latency_estimate(a, &l), BINGHAM_ERR_NOT_CONVERGED);
    check_msg(fn, "informative motion");
    CHECK(untouched(&l, sizeof l));
    /* 40 s at 100 Hz: a spin of 4 +- 1.5 rad/s about a tilted axis plus a swinging rate about a
     * perpendicular one; gyro sample k turns the truth from k-1 to k; the magnetometer shows the
     * orientation two samples (20 ms) earlier; no noise. */
    enum { N = 4000, DELAY = 2 };
    static double truth[N][4];
    double qt[4] = {1.0, 0.0, 0.0, 0.0};
    const double axis[3] = {0.4596, 0.6128, 0.6428}, perp[3] = {0.8, -0.6, 0.0};
    const double field[3] = {0.0, 25.0, -43.30127018922193}, up[3] = {0.0, 0.0, 9.81};
    for (int k = 0; k < N; ++k) {
        double t = 0.01 * k - 0.005;
        double sa = 4.0 + 1.5 * sin(2.0 * PI * 0.4 * t), sb = 1.5 * sin(2.0 * PI * 0.9 * t + 1.0);
        double g[3], acc[3], mag[3];
        for (int i = 0; i < 3; ++i) g[i] = sa * axis[i] + sb * perp[i];
        if (k > 0) {
            double th = 0.01 * sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]), s = sin(th / 2.0) / th * 0.01;
            double dq[4] = {cos(th / 2.0), s * g[0], s * g[1], s * g[2]};
            qmul(qt, dq, qt);
        }
        memcpy(truth[k], qt, sizeof qt);
        to_sensor(qt, up, acc);
        to_sensor(truth[k < DELAY ? 0 : k - DELAY], field, mag);
        CHECK_OK(bingham_ahrs_update(a, g, acc, mag));
    }
    astate s = asnap(a);
    CHECK_OK(bingham_ahrs_mag_latency_estimate(a, &l));
    CHECK(fabs(l - 0.02) < 1e-4);
    CHECK(same_state(s, asnap(a)));
    bingham_ahrs_free(a);
}

/* ---- the missing times of the health readout ----------------------------------------------- */

static void check_missing(const bingham_ahrs *a, double gyr, double acc, double mag) {
    bingham_ahrs_health_report h;
    hsnap(a, &h);
    const double got[3] = {h.gyr_missing_time, h.acc_missing_time, h.mag_missing_time}, want[3] = {gyr, acc, mag};
    for (int i = 0; i < 3; ++i) {
        if (want[i] == 0.0) CHECK(got[i] == 0.0);
        else CHECK_CLOSE(got[i], want[i], 1e-12);
    }
}

static void test_ahrs_missing_times(void) {
    double g[3], acc[3], mag[3];
    const double nan_row[3] = {NAN, NAN, NAN}, zero[3] = {0.0, 0.0, 0.0};
    bingham_ahrs *a = new_ahrs(0.01);
    if (!a) return;
    check_missing(a, 0.0, 0.0, 0.0); /* before the first sample */
    /* a first sample without a magnetometer: nothing missing yet; the magnetometer's time then
     * counts from it */
    sample(0, g, acc, mag);
    CHECK_OK(bingham_ahrs_update(a, g, acc, NULL));
    check_missing(a, 0.0, 0.0, 0.0);
    for (int k = 1; k <= 100; ++k) {
        sample(k, g, acc, mag);
        CHECK_OK(bingham_ahrs_update(a, g, acc, NULL));
    }
    check_missing(a, 0.0, 0.0, 1.0);
    /* a zero field is no sample: the count goes on; a field resets it */
    sample(101, g, acc, mag);
    CHECK_OK(bingham_ahrs_update(a, g, acc, zero));
    check_missing(a, 0.0, 0.0, 1.01);
    CHECK_OK(bingham_ahrs_update(a, g, acc, mag));
    check_missing(a, 0.0, 0.0, 0.0);
    /* free fall (|acc| < gravity/4): no accelerometer sample */
    const double fall[3] = {0.0, 0.3, 1.0};
    CHECK_OK(bingham_ahrs_update(a, g, fall, mag));
    check_missing(a, 0.0, 0.01, 0.0);
    CHECK_OK(bingham_ahrs_update(a, g, fall, mag));
    check_missing(a, 0.0, 0.02, 0.0);
    CHECK_OK(bingham_ahrs_update(a, g, acc, mag));
    check_missing(a, 0.0, 0.0, 0.0);
    /* update_dt: the sample's own step is added */
    CHECK_OK(bingham_ahrs_update_dt(a, 0.05, nan_row, acc, mag));
    check_missing(a, 0.05, 0.0, 0.0);
    CHECK_OK(bingham_ahrs_update_dt(a, 0.03, nan_row, nan_row, mag));
    check_missing(a, 0.08, 0.03, 0.0);
    CHECK_OK(bingham_ahrs_update_dt(a, 0.02, g, nan_row, nan_row));
    check_missing(a, 0.0, 0.05, 0.02);
    CHECK_OK(bingham_ahrs_update_dt(a, 0.01, g, acc, mag));
    check_missing(a, 0.0, 0.0, 0.0);
    /* a timed batch: the steps between the timestamps (the first one's, after an untimed
     * update, sample_time) */
    {
        double t[4] = {50.0, 50.02, 50.05, 50.25}, gg[12], aa[12], mm[12], q[16];
        for (int k = 0; k < 4; ++k) {
            sample(110 + k, gg + 3 * k, aa + 3 * k, mm + 3 * k);
            if (k > 0) gg[3 * k] = NAN;
        }
        CHECK_OK(bingham_ahrs_update_batch_timed(a, 4, t, gg, aa, mm, q, NULL, NULL));
        check_missing(a, (50.25 - 50.05) + (50.05 - 50.02) + (50.02 - 50.0), 0.0, 0.0);
        double t1 = 50.26;
        CHECK_OK(bingham_ahrs_update_batch_timed(a, 1, &t1, g, acc, mag, q, NULL, NULL));
        check_missing(a, 0.0, 0.0, 0.0);
    }
    bingham_ahrs_free(a);
}

/* ---- bingham_ahrs_update_dt -------------------------------------------------------------------- */

/* The rotation angle (rad) between two unit quaternions. */
static double angle_between(const double *p, const double *q) {
    double d = fabs(p[0] * q[0] + p[1] * q[1] + p[2] * q[2] + p[3] * q[3]);
    return 2.0 * acos(d > 1.0 ? 1.0 : d);
}

/* Sample k of sample() with motion (a swinging rate about x) and, if `gaps`, NaN rows: the
 * gyroscope every 13th, the accelerometer every 17th (never in sample 0), the magnetometer
 * every 5th. */
static void moving_sample(int k, int gaps, double *g, double *acc, double *mag) {
    sample(k, g, acc, mag);
    g[0] += 0.5 * sin(0.05 * k);
    if (!gaps) return;
    if (k % 13 == 5) g[1] = NAN;
    if (k % 17 == 3) acc[2] = NAN;
    if (k % 5 == 2) mag[0] = NAN;
}

static void test_ahrs_update_dt(void) {
    const char *fn = "bingham_ahrs_update_dt";
    double g[3], acc[3], mag[3];
    const double nan_row[3] = {NAN, NAN, NAN};
    bingham_ahrs *a = new_ahrs(0.01), *ref = new_ahrs(0.01);
    if (!a || !ref) return;
    /* update_dt(sample_time) == update, bit for bit: from a fresh AHRS, 300 samples in motion
     * with NaN rows in every channel and mag NULL in every third */
    int same_all = 1;
    for (int k = 0; k < 300; ++k) {
        moving_sample(k, 1, g, acc, mag);
        const double *m = k % 3 == 1 ? NULL : mag;
        CHECK_OK(bingham_ahrs_update_dt(a, 0.01, g, acc, m));
        CHECK_OK(bingham_ahrs_update(ref, g, acc, m));
        same_all &= same_state(asnap(a), asnap(ref));
    }
    CHECK(same_all);
    /* the first sample's dt is not used (the AHRS starts from it) */
    {
        bingham_ahrs *f1 = new_ahrs(0.01), *f2 = new_ahrs(0.01);
        if (!f1 || !f2) return;
        moving_sample(0, 0, g, acc, mag);
        CHECK_OK(bingham_ahrs_update_dt(f1, 0.5, g, acc, mag));
        CHECK_OK(bingham_ahrs_update(f2, g, acc, mag));
        CHECK(same_state(asnap(f1), asnap(f2)));
        bingham_ahrs_free(f1);
        bingham_ahrs_free(f2);
    }
    /* dt is used: after a steady turn of 0.3 rad/s about z (the sensor's last rate), without
     * accelerometer and magnetometer samples, the estimate turns by 0.15 rad in dt = 0.5 s,
     * by 0.003 rad in sample_time */
    {
        bingham_ahrs *c1 = new_ahrs(0.01), *c2 = NULL;
        if (!c1) return;
        for (int k = 0; k < 300; ++k) {
            sample(k, g, acc, mag);
            CHECK_OK(bingham_ahrs_update(c1, g, acc, mag));
        }
        CHECK_OK(bingham_ahrs_clone(c1, &c2));
        if (!c2) return;
        double q0[4], q1[4], q2[4];
        CHECK_OK(bingham_ahrs_quaternion(c1, q0));
        sample(300, g, acc, mag);
        CHECK_OK(bingham_ahrs_update_dt(c1, 0.5, g, nan_row, NULL));
        CHECK_OK(bingham_ahrs_update_dt(c2, 0.01, g, nan_row, NULL));
        CHECK_OK(bingham_ahrs_quaternion(c1, q1));
        CHECK_OK(bingham_ahrs_quaternion(c2, q2));
        const double a1 = angle_between(q0, q1), a2 = angle_between(q0, q2);
        if (fabs(a1 - 0.15) > 0.003 || fabs(a2 - 0.003) > 1e-4) fprintf(stderr, "    turns %g, %g\n", a1, a2);
        CHECK(fabs(a1 - 0.15) <= 0.003 && fabs(a2 - 0.003) <= 1e-4);
        bingham_ahrs_free(c1);
        bingham_ahrs_free(c2);
    }
    /* a bad dt: refused, the AHRS unchanged (getters and readout; a clone taken before, fed the
     * same next sample, stays identical), whatever the sample holds */
    {
        const double bad_dt[12] = {0.0,  -0.0,  -0.01, NAN, INFINITY, -INFINITY, 1e-7, 0.999e-6,
                                   10.000001, 11.0, 1e300, -DBL_MAX};
        bingham_ahrs *before = NULL;
        CHECK_OK(bingham_ahrs_clone(a, &before));
        if (!before) return;
        astate s = asnap(a);
        moving_sample(300, 0, g, acc, mag);
        for (int k = 0; k < 12; ++k) {
            CHECK_STATUS(bingham_ahrs_update_dt(a, bad_dt[k], k % 2 ? nan_row : g, acc, k % 3 ? mag : NULL),
                         BINGHAM_ERR_INVALID_ARGUMENT);
            check_msg(fn, "dt");
            CHECK(same_state(s, asnap(a)));
        }
        CHECK_OK(bingham_ahrs_update(a, g, acc, mag));
        CHECK_OK(bingham_ahrs_update(before, g, acc, mag));
        CHECK(same_state(asnap(a), asnap(before)));
        bingham_ahrs_free(before);
        /* the bounds themselves: accepted (on clones) */
        const double good_dt[2] = {BINGHAM_AHRS_MIN_SAMPLE_TIME, BINGHAM_AHRS_MAX_STEP_TIME};
        CHECK(BINGHAM_AHRS_MAX_STEP_TIME == 10.0);
        for (int k = 0; k < 2; ++k) {
            bingham_ahrs *c = NULL;
            CHECK_OK(bingham_ahrs_clone(a, &c));
            if (!c) return;
            CHECK_OK(bingham_ahrs_update_dt(c, good_dt[k], g, acc, mag));
            astate t = asnap(c);
            CHECK(all_finite(t.q, 4) && all_finite(t.m, 16) && all_finite(t.spread, 4) && all_finite(t.ocov, 9));
            bingham_ahrs_free(c);
        }
    }
    /* before the first sample: a bad dt refused, the AHRS stays uninitialized */
    {
        bingham_ahrs *f = new_ahrs(0.01);
        if (!f) return;
        astate s0 = asnap(f);
        moving_sample(0, 0, g, acc, mag);
        CHECK_STATUS(bingham_ahrs_update_dt(f, NAN, g, acc, mag), BINGHAM_ERR_INVALID_ARGUMENT);
        check_msg(fn, "dt");
        CHECK_STATUS(bingham_ahrs_update_dt(f, 0.0, g, acc, mag), BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK(same_state(s0, asnap(f)));
        bingham_ahrs_free(f);
    }
    /* the gyroscope's limit is on the turn |gyr| * dt: 5e7 rad/s is 5e5 rad in 0.01 s
     * (accepted, on a clone: the estimate stays a valid state), 5e6 rad in 0.1 s (refused) */
    {
        const double fast[3] = {5e7, 0.0, 0.0};
        bingham_ahrs *c = NULL;
        CHECK_OK(bingham_ahrs_clone(a, &c));
        if (!c) return;
        CHECK_OK(bingham_ahrs_update_dt(c, 0.01, fast, acc, mag));
        astate t = asnap(c);
        CHECK(all_finite(t.q, 4) && all_finite(t.m, 16) && all_finite(t.z, 4) && all_finite(t.spread, 4));
        bingham_ahrs_free(c);
        astate s = asnap(a);
        CHECK_STATUS(bingham_ahrs_update_dt(a, 0.1, fast, acc, mag), BINGHAM_ERR_INVALID_ARGUMENT);
        check_msg(fn, "gyroscope");
        CHECK(same_state(s, asnap(a)));
    }
    /* NULLs (before a bad dt too), the AHRS unchanged; mag NULL accepted */
    {
        astate s = asnap(a);
        CHECK_STATUS(bingham_ahrs_update_dt(NULL, 0.01, g, acc, mag), BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "a");
        CHECK_STATUS(bingham_ahrs_update_dt(a, 0.01, NULL, acc, mag), BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "gyr");
        CHECK_STATUS(bingham_ahrs_update_dt(a, 0.01, g, NULL, mag), BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "acc");
        CHECK_STATUS(bingham_ahrs_update_dt(a, NAN, g, NULL, mag), BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "acc");
        CHECK(same_state(s, asnap(a)));
        CHECK_OK(bingham_ahrs_update_dt(a, 0.012, g, acc, NULL));
    }
    /* a gyroscope gap in motion (10 samples without any sensor) widens the spread beyond that
     * of the same stretch with the gyroscope present */
    {
        bingham_ahrs *c1 = NULL, *c2 = NULL;
        CHECK_OK(bingham_ahrs_clone(a, &c1));
        CHECK_OK(bingham_ahrs_clone(a, &c2));
        if (!c1 || !c2) return;
        for (int k = 301; k < 311; ++k) {
            moving_sample(k, 0, g, acc, mag);
            CHECK_OK(bingham_ahrs_update(c1, nan_row, nan_row, nan_row));
            CHECK_OK(bingham_ahrs_update(c2, g, nan_row, nan_row));
        }
        double s1[4], s2[4];
        CHECK_OK(bingham_ahrs_angular_spread(c1, s1));
        CHECK_OK(bingham_ahrs_angular_spread(c2, s2));
        if (!(s1[3] > s2[3])) fprintf(stderr, "    spread with the gap %.17g, without %.17g\n", s1[3], s2[3]);
        CHECK(s1[3] > s2[3] && s2[3] > 0.0);
        check_missing(c1, 0.1, 0.1, 0.112); /* (the sample before had no magnetometer) */
        bingham_ahrs_free(c1);
        bingham_ahrs_free(c2);
    }
    bingham_ahrs_free(a);
    bingham_ahrs_free(ref);
}

/* ---- bingham_ahrs_update_batch_timed ----------------------------------------------------------- */

enum { TN = 300 };
static double tg[3 * TN], tacc[3 * TN], tmag[3 * TN];

/* quat, spread and health rows of a reference run (one timed or untimed batch, or pieces). */
typedef struct {
    double quat[4 * TN], spread[TN], health[TN];
} rows_t;

static void test_ahrs_batch_timed(void) {
    const char *fn = "bingham_ahrs_update_batch_timed";
    static rows_t r1, r2;
    static double t[TN];
    for (int k = 0; k < TN; ++k) moving_sample(k, 1, tg + 3 * k, tacc + 3 * k, tmag + 3 * k);
    /* uniformly spaced timestamps (any origin) == bingham_ahrs_update_batch_health, bit for bit,
     * with each optional argument present or NULL; from a fresh AHRS (the first sample's step is
     * sample_time) */
    for (int k = 0; k < TN; ++k) t[k] = 12345.678 + 0.01 * k;
    for (int variant = 0; variant < 8; ++variant) { /* bit 0: mag, bit 1: spread, bit 2: health */
        bingham_ahrs *a = new_ahrs(0.01), *ref = new_ahrs(0.01);
        if (!a || !ref) return;
        const double *m = variant & 1 ? tmag : NULL;
        double *sp1 = variant & 2 ? r1.spread : NULL, *h1 = variant & 4 ? r1.health : NULL;
        double *sp2 = variant & 2 ? r2.spread : NULL, *h2 = variant & 4 ? r2.health : NULL;
        fill(&r1, sizeof r1);
        fill(&r2, sizeof r2);
        CHECK_OK(bingham_ahrs_update_batch_timed(a, TN, t, tg, tacc, m, r1.quat, sp1, h1));
        CHECK_OK(bingham_ahrs_update_batch_health(ref, TN, tg, tacc, m, r2.quat, sp2, h2));
        CHECK(memcmp(&r1, &r2, sizeof r1) == 0);
        if (!sp1) CHECK(untouched(r1.spread, sizeof r1.spread));
        if (!h1) CHECK(untouched(r1.health, sizeof r1.health));
        if (sp1) CHECK(all_finite(r1.spread, TN));
        CHECK(same_state(asnap(a), asnap(ref)));
        bingham_ahrs_free(a);
        bingham_ahrs_free(ref);
    }
    /* jitter and dropped samples: a batch split anywhere == one call */
    t[0] = 3.0;
    for (int k = 1; k < TN; ++k) t[k] = t[k - 1] + 0.01 * (1.0 + 0.3 * sin(1.7 * k)) + (k % 37 == 0 ? 0.03 : 0.0);
    {
        bingham_ahrs *a = new_ahrs(0.01), *b = new_ahrs(0.01);
        if (!a || !b) return;
        fill(&r1, sizeof r1);
        fill(&r2, sizeof r2);
        CHECK_OK(bingham_ahrs_update_batch_timed(a, TN, t, tg, tacc, tmag, r1.quat, r1.spread, r1.health));
        const int pieces[7] = {1, 0, 7, 50, 1, 0, 141};
        int at = 0;
        for (int i = 0; i < 7 || at < TN; ++i) {
            const int n = i < 7 ? pieces[i] : TN - at;
            CHECK_OK(bingham_ahrs_update_batch_timed(b, (size_t)n, t + at, tg + 3 * at, tacc + 3 * at, tmag + 3 * at,
                                                     r2.quat + 4 * at, r2.spread + at, r2.health + at));
            at += n;
        }
        CHECK(memcmp(&r1, &r2, sizeof r1) == 0 && same_state(asnap(a), asnap(b)));
        /* the irregular steps are used: not the untimed batch's results */
        bingham_ahrs *u = new_ahrs(0.01);
        if (!u) return;
        CHECK_OK(bingham_ahrs_update_batch_health(u, TN, tg, tacc, tmag, r2.quat, r2.spread, r2.health));
        CHECK(memcmp(r1.quat, r2.quat, sizeof r1.quat) != 0);
        bingham_ahrs_free(u);

        /* the step of t[0]: from the previous timed batch's last timestamp */
        double g[3], acc[3], mag[3], tn = t[TN - 1] + 0.037;
        moving_sample(TN, 0, g, acc, mag);
        CHECK_OK(bingham_ahrs_update_batch_timed(a, 1, &tn, g, acc, mag, r1.quat, NULL, NULL));
        CHECK_OK(bingham_ahrs_update_dt(b, tn - t[TN - 1], g, acc, mag));
        CHECK(same_state(asnap(a), asnap(b)));
        /* ... and sample_time after an untimed update (update or update_dt) came since: then any
         * finite t[0], even one before the last timestamp, starts with sample_time */
        for (int kind = 0; kind < 2; ++kind) {
            moving_sample(TN + 1 + 2 * kind, 0, g, acc, mag);
            if (kind == 0) CHECK_OK(bingham_ahrs_update(a, g, acc, mag));
            else CHECK_OK(bingham_ahrs_update_dt(a, 0.02, g, acc, mag));
            if (kind == 0) CHECK_OK(bingham_ahrs_update(b, g, acc, mag));
            else CHECK_OK(bingham_ahrs_update_dt(b, 0.02, g, acc, mag));
            moving_sample(TN + 2 + 2 * kind, 0, g, acc, mag);
            double early = 1.0;
            CHECK_OK(bingham_ahrs_update_batch_timed(a, 1, &early, g, acc, mag, r1.quat, NULL, NULL));
            CHECK_OK(bingham_ahrs_update(b, g, acc, mag));
            CHECK(same_state(asnap(a), asnap(b)));
        }
        /* a step of exactly BINGHAM_AHRS_MAX_STEP_TIME (10 s) is accepted; then t[0] equal to
         * or before the last timestamp, or more than 10 s after it: refused at "sample 0",
         * nothing written, the AHRS unchanged */
        double t5 = 5.0, t15 = 15.0; /* (the last timestamp: 1.0) */
        CHECK_OK(bingham_ahrs_update_batch_timed(a, 1, &t5, g, acc, mag, r1.quat, NULL, NULL));
        CHECK_OK(bingham_ahrs_update_batch_timed(a, 1, &t15, g, acc, mag, r1.quat, NULL, NULL));
        const double bad0[4] = {15.0, 14.0, 25.000001, NAN};
        for (int k = 0; k < 4; ++k) {
            astate s = asnap(a);
            double tt[2] = {bad0[k], 30.0}, gg[6], aa[6], mm[6];
            for (int i = 0; i < 2; ++i) moving_sample(TN + 10 + i, 0, gg + 3 * i, aa + 3 * i, mm + 3 * i);
            fill(&r1, sizeof r1);
            CHECK_STATUS(bingham_ahrs_update_batch_timed(a, 2, tt, gg, aa, mm, r1.quat, r1.spread, r1.health),
                         BINGHAM_ERR_INVALID_ARGUMENT);
            check_msg(fn, "sample 0");
            CHECK(untouched(&r1, sizeof r1) && same_state(s, asnap(a)));
        }
        bingham_ahrs_free(a);
        bingham_ahrs_free(b);
    }
    /* a bad timestamp in sample 5 of 10 (NaN, +-Inf, equal to or before t[4], a step above 10 s
     * or below 1e-6 s) stops the batch there: rows 0..4 written and equal to a reference fed
     * only samples 0..4 (one timed batch), rows 5..9 untouched, the AHRS in the reference's
     * state; the last timestamp kept is t[4]: both continue identically */
    {
        const double base = 100.0;
        for (int kind = 0; kind < 7; ++kind) {
            double tt[10];
            for (int k = 0; k < 10; ++k) tt[k] = base + 0.01 * k;
            const double t4 = tt[4];
            const double bad5[7] = {NAN, INFINITY, -INFINITY, t4, t4 - 0.01, t4 + 10.5, t4 + 1e-7};
            tt[5] = bad5[kind];
            bingham_ahrs *a = new_ahrs(0.01), *ref = new_ahrs(0.01);
            if (!a || !ref) return;
            fill(&r1, sizeof r1);
            fill(&r2, sizeof r2);
            CHECK_STATUS(bingham_ahrs_update_batch_timed(a, 10, tt, tg, tacc, tmag, r1.quat, r1.spread, r1.health),
                         BINGHAM_ERR_INVALID_ARGUMENT);
            check_msg(fn, "sample 5");
            if (kind < 5) check_msg(fn, "timestamp");
            CHECK_OK(bingham_ahrs_update_batch_timed(ref, 5, tt, tg, tacc, tmag, r2.quat, r2.spread, r2.health));
            CHECK(memcmp(r1.quat, r2.quat, 4 * 5 * sizeof(double)) == 0);
            CHECK(memcmp(r1.spread, r2.spread, 5 * sizeof(double)) == 0);
            CHECK(memcmp(r1.health, r2.health, 5 * sizeof(double)) == 0);
            CHECK(untouched(r1.quat + 4 * 5, sizeof r1.quat - 4 * 5 * sizeof(double)));
            CHECK(untouched(r1.spread + 5, sizeof r1.spread - 5 * sizeof(double)));
            CHECK(untouched(r1.health + 5, sizeof r1.health - 5 * sizeof(double)));
            CHECK(same_state(asnap(a), asnap(ref)));
            tt[5] = t4 + 0.013;
            CHECK_OK(bingham_ahrs_update_batch_timed(a, 5, tt + 5, tg + 15, tacc + 15, tmag + 15, r1.quat, NULL, NULL));
            CHECK_OK(bingham_ahrs_update_batch_timed(ref, 5, tt + 5, tg + 15, tacc + 15, tmag + 15, r2.quat, NULL, NULL));
            CHECK(same_state(asnap(a), asnap(ref)));
            bingham_ahrs_free(a);
            bingham_ahrs_free(ref);
        }
    }
    /* a huge gyroscope row stops a timed batch too; NaN gyroscope rows do not (above) */
    {
        bingham_ahrs *a = new_ahrs(0.01);
        if (!a) return;
        double tt[4] = {0.0, 0.01, 0.02, 0.03}, gg[12];
        memcpy(gg, tg, sizeof gg);
        gg[3 * 2 + 1] = 1e12;
        fill(&r1, sizeof r1);
        CHECK_STATUS(bingham_ahrs_update_batch_timed(a, 4, tt, gg, tacc, tmag, r1.quat, NULL, NULL),
                     BINGHAM_ERR_INVALID_ARGUMENT);
        check_msg(fn, "sample 2");
        CHECK(untouched(r1.quat + 8, sizeof r1.quat - 8 * sizeof(double)));
        bingham_ahrs_free(a);
    }
    /* NULLs: refused, nothing written, the AHRS unchanged; n = 0 does nothing; n * 4
     * overflowing refused before any access */
    {
        bingham_ahrs *a = new_ahrs(0.01);
        if (!a) return;
        CHECK_OK(bingham_ahrs_update_batch_timed(a, 20, t, tg, tacc, tmag, r1.quat, NULL, NULL));
        astate s = asnap(a);
        fill(&r1, sizeof r1);
        const double *tt = t + 20;
        CHECK_STATUS(bingham_ahrs_update_batch_timed(NULL, 10, tt, tg, tacc, tmag, r1.quat, r1.spread, r1.health),
                     BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "a");
        CHECK_STATUS(bingham_ahrs_update_batch_timed(a, 10, NULL, tg, tacc, tmag, r1.quat, r1.spread, r1.health),
                     BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "t");
        CHECK_STATUS(bingham_ahrs_update_batch_timed(a, 10, tt, NULL, tacc, tmag, r1.quat, r1.spread, r1.health),
                     BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "gyr");
        CHECK_STATUS(bingham_ahrs_update_batch_timed(a, 10, tt, tg, NULL, tmag, r1.quat, r1.spread, r1.health),
                     BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "acc");
        CHECK_STATUS(bingham_ahrs_update_batch_timed(a, 10, tt, tg, tacc, tmag, NULL, r1.spread, r1.health),
                     BINGHAM_ERR_NULL_ARGUMENT);
        check_null_msg(fn, "quat");
        CHECK(untouched(&r1, sizeof r1) && same_state(s, asnap(a)));
        CHECK_OK(bingham_ahrs_update_batch_timed(a, 0, tt, tg, tacc, tmag, r1.quat, r1.spread, r1.health));
        CHECK(untouched(&r1, sizeof r1) && same_state(s, asnap(a)));
        /* (n = SIZE_MAX / 32: n timestamps fit in the address space, n rows of 3 do not) */
        CHECK_STATUS(bingham_ahrs_update_batch_timed(a, (size_t)-1 / 32, no_access(), no_access(), no_access(), NULL,
                                                     no_access(), NULL, NULL),
                     BINGHAM_ERR_INVALID_DIMENSION);
        check_msg(fn, NULL);
        CHECK(same_state(s, asnap(a)));
        /* n = 0 kept the last timestamp: the batch continues as one call would */
        bingham_ahrs *b = new_ahrs(0.01);
        if (!b) return;
        CHECK_OK(bingham_ahrs_update_batch_timed(b, 30, t, tg, tacc, tmag, r2.quat, NULL, NULL));
        CHECK_OK(bingham_ahrs_update_batch_timed(a, 10, tt, tg + 60, tacc + 60, tmag + 60, r1.quat, NULL, NULL));
        CHECK(same_state(asnap(a), asnap(b)));
        bingham_ahrs_free(a);
        bingham_ahrs_free(b);
    }
}

/* ---- bingham_ahrs_orientation_covariance --------------------------------------------------------- */

/* cov: finite, symmetric, positive semi-definite (every principal minor >= 0 up to rounding),
 * its trace the square of the total spread within 1e-12 relative. */
static void check_orientation_cov(const bingham_ahrs *a, const char *where) {
    double c[9], sp[4];
    CHECK_OK(bingham_ahrs_orientation_covariance(a, c));
    CHECK_OK(bingham_ahrs_angular_spread(a, sp));
    const double tr = c[0] + c[4] + c[8], eps = 1e-13 * tr;
    int ok = all_finite(c, 9) && tr > 0.0;
    for (int i = 0; i < 3; ++i) {
        ok &= c[4 * i] >= 0.0;
        for (int j = 0; j < 3; ++j) ok &= fabs(c[3 * i + j] - c[3 * j + i]) <= 1e-15 * tr;
    }
    for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3;
        ok &= c[4 * i] * c[4 * j] - c[3 * i + j] * c[3 * j + i] >= -eps * tr;
    }
    const double det = c[0] * (c[4] * c[8] - c[5] * c[7]) - c[1] * (c[3] * c[8] - c[5] * c[6]) +
                       c[2] * (c[3] * c[7] - c[4] * c[6]);
    ok &= det >= -eps * tr * tr;
    const double s2 = sp[3] * sp[3];
    ok &= fabs(tr - s2) <= 1e-12 * s2;
    if (!ok)
        fprintf(stderr, "    %s: cov [%g %g %g; %g %g %g; %g %g %g], trace %.17g, spread^2 %.17g\n", where, c[0], c[1],
                c[2], c[3], c[4], c[5], c[6], c[7], c[8], tr, s2);
    CHECK(ok);
}

static void test_ahrs_orientation_covariance(void) {
    const char *fn = "bingham_ahrs_orientation_covariance";
    double c[9], g[3], acc[3], mag[3];
    bingham_ahrs *a = new_ahrs(0.01);
    if (!a) return;
    /* before the first sample: the identity (a uniform orientation's), trace == spread^2 */
    fill(c, sizeof c);
    CHECK_OK(bingham_ahrs_orientation_covariance(a, c));
    for (int i = 0; i < 9; ++i) CHECK(c[i] == (i % 4 == 0 ? 1.0 : 0.0));
    check_orientation_cov(a, "before the first sample");
    /* NULLs: refused, the output untouched, the AHRS unchanged */
    astate s0 = asnap(a);
    fill(c, sizeof c);
    CHECK_STATUS(bingham_ahrs_orientation_covariance(NULL, c), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fn, "a");
    CHECK_STATUS(bingham_ahrs_orientation_covariance(a, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fn, "cov");
    CHECK(untouched(c, sizeof c) && same_state(s0, asnap(a)));
    /* after every one of 600 samples in motion with gaps (between corrections too: the process
     * noise since the last one included) */
    for (int k = 0; k < 600; ++k) {
        moving_sample(k, 1, g, acc, mag);
        CHECK_OK(bingham_ahrs_update(a, g, acc, mag));
        check_orientation_cov(a, "in motion");
    }
    /* a readout changes nothing; errors after samples leave the output untouched */
    astate s1 = asnap(a);
    CHECK(same_state(s1, asnap(a)));
    fill(c, sizeof c);
    CHECK_STATUS(bingham_ahrs_orientation_covariance(NULL, c), BINGHAM_ERR_NULL_ARGUMENT);
    CHECK(untouched(c, sizeof c));
    bingham_ahrs_free(a);

    /* the world frame: a sensor tilted by 60 deg about x, without magnetometer: the unknown
     * heading is the variance about world z (up); about the sensor's z axis, (0, sin 60,
     * cos 60) in the world, it would show in the world's yy as well */
    a = new_ahrs(0.01);
    if (!a) return;
    const double th = PI / 3.0, zero[3] = {0.0, 0.0, 0.0};
    const double tilted[3] = {0.0, 9.81 * sin(th), 9.81 * cos(th)};
    for (int k = 0; k < 500; ++k) {
        CHECK_OK(bingham_ahrs_update(a, zero, tilted, NULL));
        if (k % 50 == 0) check_orientation_cov(a, "tilted, 6-D");
    }
    CHECK_OK(bingham_ahrs_orientation_covariance(a, c));
    if (!(c[8] > 1e3 * c[0] && c[8] > 1e3 * c[4]))
        fprintf(stderr, "    tilted 6-D: diag %g %g %g\n", c[0], c[4], c[8]);
    CHECK(c[8] > 1e3 * c[0] && c[8] > 1e3 * c[4]);
    CHECK(fabs(c[2]) < 1e-3 * c[8] && fabs(c[5]) < 1e-3 * c[8]);

    /* a state set with set_state: its principal spreads on the world axes. Mode (1, 0, 0, 0),
     * columns k, j, i (z = -400, -100, -25): diag(spread[2]^2, spread[1]^2, spread[0]^2).
     * Mode q = 90 deg about z, columns q(x)i, q(x)j, q(x)k: the body axes x, y, z, which the
     * world sees as y, -x, z: diag(spread[1]^2, spread[0]^2, spread[2]^2) */
    {
        const double z[4] = {-400.0, -100.0, -25.0, 0.0};
        const double h = sqrt(0.5), q[4] = {h, 0.0, 0.0, h};
        const double l[4][4] = {{q[0], -q[1], -q[2], -q[3]},
                                {q[1], q[0], -q[3], q[2]},
                                {q[2], q[3], q[0], -q[1]},
                                {q[3], -q[2], q[1], q[0]}};
        double m1[16] = {0}, m2[16], sp[4];
        for (int i = 0; i < 4; ++i) m1[i * 4 + (3 - i)] = 1.0;
        for (int k = 0; k < 16; ++k) m2[k] = l[k / 4][(k % 4 + 1) % 4];
        for (int which = 0; which < 2; ++which) {
            CHECK_OK(bingham_ahrs_set_state(a, which ? m2 : m1, z));
            CHECK_OK(bingham_ahrs_orientation_covariance(a, c));
            CHECK_OK(bingham_ahrs_angular_spread(a, sp));
            check_orientation_cov(a, "after set_state");
            const double want[3] = {which ? sp[1] * sp[1] : sp[2] * sp[2], which ? sp[0] * sp[0] : sp[1] * sp[1],
                                    which ? sp[2] * sp[2] : sp[0] * sp[0]};
            const double tr = c[0] + c[4] + c[8];
            for (int i = 0; i < 3; ++i) {
                CHECK(fabs(c[4 * i] - want[i]) <= 1e-12 * tr);
                for (int j = 0; j < 3; ++j)
                    if (i != j) CHECK(fabs(c[3 * i + j]) <= 1e-12 * tr);
            }
        }
    }
    bingham_ahrs_free(a);
}

/* ---- bingham_ahrs_smooth, bingham_ahrs_smooth_ex -------------------------------------------------- */

enum { SN = 400 };

static void test_ahrs_smooth(void) {
    const char *fn = "bingham_ahrs_smooth", *fx = "bingham_ahrs_smooth_ex";
    static double g[3 * SN], acc[3 * SN], mag[3 * SN], t[SN];
    static double q1[4 * SN], q2[4 * SN], s1[SN], s2[SN], b2[3 * SN], c2[9 * SN], qo[4 * SN];
    bingham_ahrs_params p;
    CHECK_OK(bingham_ahrs_params_default(0.01, &p));
    /* the slow turn about z: the truth is the yaw 0.3 t, q = (cos(yaw/2), 0, 0, sin(yaw/2)) */
    for (int k = 0; k < SN; ++k) {
        sample(k, g + 3 * k, acc + 3 * k, mag + 3 * k);
        t[k] = 500.0 + 0.01 * k;
    }
    CHECK_OK(bingham_ahrs_smooth(&p, SN, g, acc, mag, q1, s1));
    double worst = 0.0;
    int unit = 1;
    for (int k = 0; k < SN; ++k) {
        const double yaw = 0.3 * 0.01 * k, *q = q1 + 4 * k;
        const double d = fabs(q[0] * cos(yaw / 2) + q[3] * sin(yaw / 2));
        const double e = 2.0 * acos(d < 1.0 ? d : 1.0);
        worst = e > worst ? e : worst;
        unit &= fabs(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] - 1.0) < 1e-12 && q[0] >= 0.0;
        unit &= isfinite(s1[k]) && s1[k] > 0.0;
    }
    CHECK(unit);
    if (worst > 1.0 * PI / 180.0) fprintf(stderr, "    smooth: worst error %g deg\n", worst * 180.0 / PI);
    CHECK(worst <= 1.0 * PI / 180.0);
    /* the last sample has no future: it is the online AHRS's, bit for bit */
    bingham_ahrs *a = new_ahrs(0.01);
    if (!a) return;
    CHECK_OK(bingham_ahrs_update_batch(a, SN, g, acc, mag, qo));
    CHECK(memcmp(q1 + 4 * (SN - 1), qo + 4 * (SN - 1), 4 * sizeof(double)) == 0);
    bingham_ahrs_free(a);
    /* the extended call: uniformly spaced timestamps, the further outputs; the same rows bit for
     * bit; the spread the square root of the covariance's trace; the bias near the truth's
     * (0.001, -0.002, 0) rad/s */
    CHECK_OK(bingham_ahrs_smooth_ex(&p, SN, t, g, acc, mag, q2, s2, b2, c2));
    CHECK(memcmp(q1, q2, sizeof q1) == 0 && memcmp(s1, s2, sizeof s1) == 0);
    int cov_ok = 1;
    for (int k = 0; k < SN; ++k) {
        const double *c = c2 + 9 * k, tr = c[0] + c[4] + c[8];
        cov_ok &= fabs(sqrt(tr) - s2[k]) <= 1e-6 * s2[k] && c[1] == c[3] && c[2] == c[6] && c[5] == c[7];
        cov_ok &= all_finite(b2 + 3 * k, 3) && fabs(b2[3 * k + 2]) < 0.01;
    }
    CHECK(cov_ok);
    /* NaN rows in every channel (no sample) and mag NULL: processed */
    for (int k = 0; k < SN; ++k) moving_sample(k, 1, g + 3 * k, acc + 3 * k, mag + 3 * k);
    CHECK_OK(bingham_ahrs_smooth(&p, SN, g, acc, mag, q1, NULL));
    CHECK_OK(bingham_ahrs_smooth(&p, SN, g, acc, NULL, q1, s1));
    CHECK(all_finite(q1, 4 * SN) && all_finite(s1, SN));
    for (int k = 0; k < SN; ++k) sample(k, g + 3 * k, acc + 3 * k, mag + 3 * k);
    /* errors: nothing written, the message names the function (and the argument) */
    fill(q1, sizeof q1), fill(s1, sizeof s1), fill(b2, sizeof b2), fill(c2, sizeof c2);
    CHECK_STATUS(bingham_ahrs_smooth(NULL, SN, g, acc, mag, q1, s1), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fn, "p");
    CHECK_STATUS(bingham_ahrs_smooth(&p, SN, NULL, acc, mag, q1, s1), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fn, "gyr");
    CHECK_STATUS(bingham_ahrs_smooth(&p, SN, g, NULL, mag, q1, s1), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fn, "acc");
    CHECK_STATUS(bingham_ahrs_smooth(&p, SN, g, acc, mag, NULL, s1), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fn, "quat");
    CHECK_STATUS(bingham_ahrs_smooth_ex(NULL, SN, t, g, acc, mag, q1, s1, b2, c2), BINGHAM_ERR_NULL_ARGUMENT);
    check_null_msg(fx, "p");
    /* the first sample without gravity: refused at sample 0 */
    acc[2] = NAN;
    CHECK_STATUS(bingham_ahrs_smooth(&p, SN, g, acc, mag, q1, s1), BINGHAM_ERR_INVALID_ARGUMENT);
    check_msg(fn, "sample 0");
    acc[2] = 9.81;
    /* a gyroscope row turning more than 1e6 rad late in the recording */
    g[3 * (SN - 2)] = 1e300;
    CHECK_STATUS(bingham_ahrs_smooth_ex(&p, SN, t, g, acc, mag, q1, s1, b2, c2), BINGHAM_ERR_INVALID_ARGUMENT);
    check_msg(fx, "sample");
    g[3 * (SN - 2)] = 0.001;
    /* a timestamp not after the previous one */
    t[SN / 2] = t[SN / 2 - 1];
    CHECK_STATUS(bingham_ahrs_smooth_ex(&p, SN, t, g, acc, mag, q1, s1, b2, c2), BINGHAM_ERR_INVALID_ARGUMENT);
    check_msg(fx, "timestamp");
    t[SN / 2] = 500.0 + 0.01 * (SN / 2);
    /* a bad parameter */
    bingham_ahrs_params bad = p;
    bad.sample_time = NAN;
    CHECK_STATUS(bingham_ahrs_smooth(&bad, SN, g, acc, mag, q1, s1), BINGHAM_ERR_INVALID_ARGUMENT);
    /* n * 4 overflowing, the arrays aimed at an inaccessible page: nothing read */
    CHECK_STATUS(bingham_ahrs_smooth_ex(&p, (size_t)-1 / 4, no_access(), no_access(), no_access(), NULL, no_access(),
                                        NULL, NULL, NULL),
                 BINGHAM_ERR_INVALID_DIMENSION);
    check_msg(fx, NULL);
    /* n = 0: nothing to do */
    CHECK_OK(bingham_ahrs_smooth(&p, 0, g, acc, mag, q1, s1));
    CHECK(untouched(q1, sizeof q1) && untouched(s1, sizeof s1) && untouched(b2, sizeof b2) &&
          untouched(c2, sizeof c2));
    /* n = 1: the online AHRS's first estimate */
    CHECK_OK(bingham_ahrs_smooth(&p, 1, g, acc, mag, q1, NULL));
    CHECK(memcmp(q1, qo, 4 * sizeof(double)) == 0);
}

int main(void) {
    if (guard_pages_init()) return 1;
    (void)PI;
    test_vector_observation();
    test_noise_from_angle_std();
    test_angular_spread();
    test_filter_vector();
    test_ahrs_params_and_new();
    test_ahrs_update();
    test_ahrs_batch();
    test_ahrs_health();
    test_ahrs_batch_health();
    test_ahrs_bias_uncertainty();
    test_ahrs_gyro_scale();
    test_ahrs_latency();
    test_ahrs_missing_times();
    test_ahrs_update_dt();
    test_ahrs_batch_timed();
    test_ahrs_orientation_covariance();
    test_ahrs_smooth();
    return check_summary("ahrs_api");
}
