/* Orientation tracking with nonlinear models through C callbacks: a nonlinear rate law for the
 * prediction (bingham_filter_predict_nonlinear) and a pinhole camera for the measurement
 * (bingham_filter_update_nonlinear). The same scenario as examples/python/nonlinear.py.
 *
 *   usage: nonlinear [steps]     (a row every 25 steps; BINGHAM_VERBOSE=1: every 10, and the
 *                                 failing callback's message)
 *
 * Quaternions are scalar first, (w, x, y, z), body -> world; q and -q are the same rotation.
 * The world frame is the frame of a fixed camera (x right, y down, z along the optical axis).
 *
 * Dynamics (nonlinear in q): the body spins about its own x axis b and b is pulled towards the
 * world's "up" (-y) with a rate that grows with the misalignment (a self-righting buoy):
 *
 *   omega(q) = GAIN (b x R(q)^T up) + SPIN b        (body frame, rad/s)
 *   q[k+1]   = q[k] (x) exp(omega(q[k]) DT) (x) w[k],   w isotropic, SIGMA_W rad per sqrt(s)
 *
 * Measurement: the camera sees three markers fixed on the body (offsets MARKERS, metres, body
 * frame) at the known position P; pixel = F (X/Z, Y/Z) + C of P + R(q) b_i, with Gaussian pixel
 * noise SIGMA_PX. The log-likelihood of the pixel residuals is a nonlinear function of q; the
 * filter receives it as a callback with the measured pixels passed through user_data.
 *
 * Both callbacks keep the sign contract: R(-q) = R(q), so rate_law(-q) = -rate_law(q) and the
 * likelihood is even. Noise comes from the library's exact sampler (fixed seed) and a small
 * fixed-seed generator for the pixels, so the output is the same on every run.
 *
 * Also shown: the deterministic samples the filter uses (bingham_deterministic_samples) and a
 * failing callback (BINGHAM_ERR_CALLBACK, the filter unchanged).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bingham.h"

#define D 4
#define MAX_STEPS 1000
#define N_MARKERS 3

static const double PI = 3.14159265358979323846;
static const double DT = 0.05;     /* s */
static const double GAIN = 1.5;    /* 1/s */
static const double SPIN = 0.8;    /* rad/s about the body x axis */
static const double SIGMA_W = 0.05; /* rad/sqrt(s) */
static const double UP[3] = {0, -1, 0};
static const double F_PX = 600.0, C_PX[2] = {320.0, 240.0};
static const double P[3] = {0.1, -0.05, 1.5};
static const double MARKERS[N_MARKERS][3] = {{0.25, 0, 0}, {0, 0.25, 0}, {0, 0, 0.25}};
static const double SIGMA_PX = 1.5;

static void check(bingham_status st, const char *what) {
    if (st != BINGHAM_OK) {
        char msg[512];
        bingham_last_error_message(msg, sizeof msg, NULL);
        fprintf(stderr, "%s failed: %s (%s)\n", what, bingham_status_str((int)st), msg);
        exit(1);
    }
}

/* ---- quaternions ------------------------------------------------------------------------- */

/* Hamilton product, scalar first */
static void qmul(const double *a, const double *b, double *out) {
    double r[D];
    int i;
    r[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    r[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    r[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    r[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
    for (i = 0; i < D; ++i) out[i] = r[i];
}

static void normalize(double *q) {
    double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    int i;
    for (i = 0; i < D; ++i) q[i] /= n;
}

/* the unit quaternion of the rotation vector v (radians) */
static void expq(const double *v, double *q) {
    double a = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    double s = a > 1e-12 ? sin(a / 2) / a : 0.5;
    q[0] = cos(a / 2);
    q[1] = s * v[0];
    q[2] = s * v[1];
    q[3] = s * v[2];
    normalize(q);
}

/* R(q), body -> world, row-major */
static void rotmat(const double *q, double r[9]) {
    double w = q[0], x = q[1], y = q[2], z = q[3];
    r[0] = 1 - 2 * (y * y + z * z); r[1] = 2 * (x * y - w * z);     r[2] = 2 * (x * z + w * y);
    r[3] = 2 * (x * y + w * z);     r[4] = 1 - 2 * (x * x + z * z); r[5] = 2 * (y * z - w * x);
    r[6] = 2 * (x * z - w * y);     r[7] = 2 * (y * z + w * x);     r[8] = 1 - 2 * (x * x + y * y);
}

/* rotation angle between two unit quaternions, radians */
static double angle(const double *a, const double *b) {
    double c = fabs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]);
    return 2 * acos(c < 1 ? c : 1);
}

/* ---- the models -------------------------------------------------------------------------- */

/* One noise-free step of the dynamics: q (x) exp(omega(q) DT). */
static void rate_law(const double *q, double *out) {
    double r[9], up_b[3], omega[3], dq[D];
    int i;
    rotmat(q, r);
    for (i = 0; i < 3; ++i) up_b[i] = r[0 * 3 + i] * UP[0] + r[1 * 3 + i] * UP[1] + r[2 * 3 + i] * UP[2];
    /* b = (1, 0, 0): b x u = (0, -u_z, u_y) */
    omega[0] = SPIN * DT;
    omega[1] = -GAIN * up_b[2] * DT;
    omega[2] = GAIN * up_b[1] * DT;
    expq(omega, dq);
    qmul(q, dq, out);
    normalize(out);
}

/* bingham_transition_fn: unit vector in, unit vector out, 0 = success */
static int transition(const double *x_in, double *x_out, void *user_data) {
    (void)user_data;
    rate_law(x_in, x_out);
    return 0;
}

/* the markers' pixels for orientation q; depths below 5 cm are clamped (a marker at or behind
 * the camera is very unlikely, not an error) */
static void project(const double *q, double pixels[N_MARKERS][2]) {
    double r[9];
    int i, k;
    rotmat(q, r);
    for (i = 0; i < N_MARKERS; ++i) {
        double c[3], depth;
        for (k = 0; k < 3; ++k)
            c[k] = P[k] + r[k * 3 + 0] * MARKERS[i][0] + r[k * 3 + 1] * MARKERS[i][1] +
                   r[k * 3 + 2] * MARKERS[i][2];
        depth = c[2] > 0.05 ? c[2] : 0.05;
        pixels[i][0] = F_PX * c[0] / depth + C_PX[0];
        pixels[i][1] = F_PX * c[1] / depth + C_PX[1];
    }
}

/* what the likelihood callback needs: the measured pixels */
typedef struct {
    double pixels[N_MARKERS][2];
    int calls;
} camera_measurement;

/* bingham_log_likelihood_fn: log L(q) of the measured pixels (up to a constant), 0 = success */
static int camera_log_likelihood(const double *q, double *log_l, void *user_data) {
    camera_measurement *meas = (camera_measurement *)user_data;
    double pred[N_MARKERS][2], s = 0;
    int i, k;
    project(q, pred);
    for (i = 0; i < N_MARKERS; ++i)
        for (k = 0; k < 2; ++k) {
            double e = pred[i][k] - meas->pixels[i][k];
            s += e * e;
        }
    *log_l = -0.5 * s / (SIGMA_PX * SIGMA_PX);
    meas->calls++;
    return 0;
}

/* a model that fails: e.g. a lookup outside its table */
static int failing_transition(const double *x_in, double *x_out, void *user_data) {
    (void)x_in;
    (void)x_out;
    (void)user_data;
    return 1;
}

/* ---- a fixed-seed normal generator for the pixel noise ----------------------------------- */

static uint64_t rng_state = 12345;

static double uniform01(void) {
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    z ^= z >> 31;
    return ((double)(z >> 11) + 0.5) / 9007199254740992.0; /* (0, 1) */
}

static double normal(void) {
    return sqrt(-2 * log(uniform01())) * cos(2 * PI * uniform01());
}

/* ---- main -------------------------------------------------------------------------------- */

int main(int argc, char **argv) {
    int steps = argc > 1 ? atoi(argv[1]) : 100;
    double mw[D * D], zw[D], m0[D * D], z0[D], m[D * D], z[D], m_after[D * D], z_after[D];
    double truth[D], start_error[D], q_off[D], v[3], mode[D], spread[D];
    double *w;
    double points[19 * D], weights[19];
    size_t count = 0, max_count = 0;
    int reproduced = 0, k, i, j, settle = (int)(1.0 / DT + 0.5), n_rms = 0, calls = 0;
    double sum_err2 = 0, sum_spread2 = 0, wsum = 0;
    bingham_filter *f = NULL;
    bingham_status st;
    const char *v_env = getenv("BINGHAM_VERBOSE");
    const int verbose = v_env && *v_env && strcmp(v_env, "0") != 0, every = verbose ? 10 : 25;

    if (steps < 1 || steps > MAX_STEPS) {
        fprintf(stderr, "steps must be in 1..%d\n", MAX_STEPS);
        return 2;
    }
    check(bingham_noise_from_angle_std(D, SIGMA_W * sqrt(DT), mw, zw), "bingham_noise_from_angle_std");
    w = (double *)malloc(sizeof(double) * D * (size_t)steps);
    if (!w) return 1;
    check(bingham_sample(D, mw, zw, 2024, (size_t)steps, w), "bingham_sample");

    /* the truth starts at exp((0.4, -0.3, 1.0)); the filter 25 degrees off with a 30 degree spread */
    v[0] = 0.4; v[1] = -0.3; v[2] = 1.0;
    expq(v, truth);
    v[0] = 0.6 * 25 * PI / 180; v[1] = 0; v[2] = 0.8 * 25 * PI / 180;
    expq(v, start_error);
    qmul(truth, start_error, q_off);
    check(bingham_noise_from_angle_std(D, 30 * PI / 180, m, z0), "bingham_noise_from_angle_std");
    for (j = 0; j < D; ++j) { /* column j of M0 = q_off (x) column j of the identity-mode noise */
        double col[D], out[D];
        for (i = 0; i < D; ++i) col[i] = m[i * D + j];
        qmul(q_off, col, out);
        for (i = 0; i < D; ++i) m0[i * D + j] = out[i];
    }

    /* the deterministic samples of the initial state (what the filter's steps use) */
    check(bingham_deterministic_sample_count(D, BINGHAM_SAMPLES_MOMENTS, &max_count),
          "bingham_deterministic_sample_count");
    check(bingham_deterministic_samples(D, m0, z0, BINGHAM_SAMPLES_MOMENTS, 0.5, max_count, points, weights,
                                        &count, &reproduced),
          "bingham_deterministic_samples");
    for (i = 0; i < (int)count; ++i) wsum += weights[i];
    printf("Nonlinear models through C callbacks (rate law, pinhole camera): %d steps of %.2f s, known truth\n",
           steps, DT);
    printf("  deterministic samples of the initial state: %u points (at most %u), weights sum to %.15f, "
           "moments reproduced up to order %d\n",
           (unsigned)count, (unsigned)max_count, wsum, reproduced);

    check(bingham_filter_new(D, m0, z0, &f), "bingham_filter_new");

    /* a failing callback: status BINGHAM_ERR_CALLBACK, message, the filter unchanged */
    check(bingham_filter_get_state(f, m, z), "bingham_filter_get_state");
    st = bingham_filter_predict_nonlinear(f, failing_transition, NULL, mw, zw);
    check(bingham_filter_get_state(f, m_after, z_after), "bingham_filter_get_state");
    {
        char msg[512];
        bingham_last_error_message(msg, sizeof msg, NULL);
        printf("  a failing transition callback: status %d (%s), filter unchanged: %s\n", (int)st,
               bingham_status_str((int)st), z[0] == z_after[0] && m[0] == m_after[0] ? "yes" : "NO");
        if (verbose) printf("  message: %s\n", msg);
        if (st != BINGHAM_ERR_CALLBACK) {
            bingham_filter_free(f);
            free(w);
            return 1;
        }
    }

    printf("  time (s)  error (deg)  spread (deg)  likelihood calls\n");
    for (k = 0; k < steps; ++k) {
        camera_measurement meas;
        double next[D];
        rate_law(truth, next);
        qmul(next, w + (size_t)k * D, truth);
        normalize(truth);

        project(truth, meas.pixels);
        for (i = 0; i < N_MARKERS; ++i)
            for (j = 0; j < 2; ++j) meas.pixels[i][j] += SIGMA_PX * normal();
        meas.calls = 0;

        check(bingham_filter_predict_nonlinear(f, transition, NULL, mw, zw), "bingham_filter_predict_nonlinear");
        check(bingham_filter_update_nonlinear(f, camera_log_likelihood, &meas), "bingham_filter_update_nonlinear");
        check(bingham_filter_mode(f, mode), "bingham_filter_mode");
        check(bingham_filter_angular_spread(f, spread), "bingham_filter_angular_spread");
        calls += meas.calls;
        if (k == 0 || k % every == every - 1)
            printf("%10.2f %12.2f %13.2f %17d\n", (k + 1) * DT, angle(mode, truth) * 180 / PI,
                   spread[D - 1] * 180 / PI, meas.calls);
        if (k >= settle) {
            double e = angle(mode, truth);
            sum_err2 += e * e;
            sum_spread2 += spread[D - 1] * spread[D - 1];
            n_rms++;
        }
    }
    bingham_filter_free(f);
    free(w);

    printf("%d likelihood calls in %d updates", calls, steps);
    if (n_rms > 0) {
        double rms = sqrt(sum_err2 / n_rms), rms_spread = sqrt(sum_spread2 / n_rms);
        printf("; after the first second: RMS error %.2f deg, RMS spread %.2f deg", rms * 180 / PI,
               rms_spread * 180 / PI);
        if (!(rms < 3 * rms_spread)) {
            fprintf(stderr, "\nthe error is not consistent with the filter's spread\n");
            return 1;
        }
    }
    printf("\n");
    return 0;
}
