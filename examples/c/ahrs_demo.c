/* The Bingham AHRS (bingham_ahrs_*) on a simulated IMU with a known motion: 60 s at 200 Hz.
 *
 *   usage: ahrs_demo            (a row every 15 s; BINGHAM_VERBOSE=1: every 5 s)
 *
 * Truth: 5 s at rest, then rotation about a slowly varying axis with smooth rates up to about
 * 2 rad/s. Conventions: q = (w, x, y, z) maps sensor to world (ENU), v_world = q v_sensor q*;
 * the gyroscope measures the body rate (rad/s), the accelerometer the specific force (+g up at
 * rest, m/s^2), the magnetometer the field in the sensor frame (uT).
 *
 *   gyroscope      white noise 0.003 rad/s per sample, constant bias (0.3, -0.2, 0.25) deg/s
 *   accelerometer  white noise 0.05 m/s^2; a 5 m/s^2 linear acceleration for 0.3 s every 7 s
 *   magnetometer   field (0, 20, -40) uT in ENU, white noise 0.3 uT; from t = 30 s to 35 s a
 *                  disturbance scales the field by 1.3
 *
 * Three AHRS: A sees every sample from t = 0 (it initializes at rest); B starts at t = 20 s in
 * the middle of the fast motion (its first sample gives tilt and heading while rotating, and
 * the linear acceleration bursts and the disturbance still come); C is told a start 180 deg
 * wrong (the truth turned upside down about the east axis) with a confident 10 deg spread
 * (bingham_ahrs_set_state before its first sample) and has to find its way back. Every 15 s (5 s
 * with BINGHAM_VERBOSE=1): the angle between
 * truth and estimate of each (deg), the predicted angular spread (the RMS of 2 sin(theta/2),
 * deg), and A's gyroscope-bias error (deg/s); at the end the RMS error after settling.
 * (Without the linear-acceleration bursts the RMS error is about 0.3 deg: horizontal bursts
 * hardly change |acc|, so they are only partly rejected and dominate the error.)
 * Deterministic: xorshift64* with Box-Muller. Only libbingham and libm.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bingham.h"

#define RATE 200.0
#define DURATION 60.0
#define START_B 20.0
static const double PI = 3.14159265358979323846;
static const double DEG = 180.0 / 3.14159265358979323846;

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;

static double uniform(void) { /* xorshift64*, in (0, 1) */
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return ((double)((rng_state * 0x2545F4914F6CDD1Dull) >> 11) + 0.5) / 9007199254740992.0;
}

static double gauss(void) { return sqrt(-2.0 * log(uniform())) * cos(2.0 * PI * uniform()); }

/* r = a (+) b, the Hamilton product, scalar first */
static void qmul(const double *a, const double *b, double *r) {
    double t[4];
    t[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    t[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    t[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    t[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
    r[0] = t[0], r[1] = t[1], r[2] = t[2], r[3] = t[3];
}

/* v_sensor = R(q)^T v_world */
static void to_sensor(const double *q, const double *v, double *out) {
    double w = q[0], x = q[1], y = q[2], z = q[3];
    double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                      {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                      {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
    for (int i = 0; i < 3; ++i) out[i] = r[0][i] * v[0] + r[1][i] * v[1] + r[2][i] * v[2];
}

/* angle (deg) of the rotation between the orientations p and q */
static double angle_between(const double *p, const double *q) {
    double d = fabs(p[0] * q[0] + p[1] * q[1] + p[2] * q[2] + p[3] * q[3]);
    return 2.0 * acos(d < 1.0 ? d : 1.0) * DEG;
}

/* the true body rate (rad/s) at time t: rest, then a smooth ramp into rotation about a
 * wandering axis, |omega| up to about 2 rad/s */
static void true_rate(double t, double *w) {
    double ramp = t < 5.0 ? 0.0 : t < 7.0 ? 0.5 - 0.5 * cos(PI * (t - 5.0) / 2.0) : 1.0;
    w[0] = ramp * 1.3 * sin(0.71 * t);
    w[1] = ramp * 1.1 * sin(0.43 * t + 1.0);
    w[2] = ramp * 0.9 * sin(0.29 * t + 2.0);
}

static int check(bingham_status st, const char *what) {
    if (st == BINGHAM_OK) return 0;
    char msg[256];
    bingham_last_error_message(msg, sizeof msg, NULL);
    fprintf(stderr, "%s failed: %s (%s)\n", what, bingham_status_str(st), msg);
    return 1;
}

int main(void) {
    const double dt = 1.0 / RATE, g_up[3] = {0.0, 0.0, 9.81}, field[3] = {0.0, 20.0, -40.0};
    const double bias[3] = {0.3 / DEG, -0.2 / DEG, 0.25 / DEG};
    const int n = (int)(DURATION * RATE + 0.5), start_b = (int)(START_B * RATE + 0.5);
    bingham_ahrs_params p;
    bingham_ahrs *a = NULL, *b = NULL, *c = NULL;
    /* the parameters from the rate in Hz (bingham_ahrs_params_default(dt, &p) takes the period) */
    if (check(bingham_ahrs_params_from_rate(RATE, &p), "bingham_ahrs_params_from_rate") ||
        check(bingham_ahrs_new(&p, &a), "bingham_ahrs_new") || check(bingham_ahrs_new(&p, &b), "bingham_ahrs_new") ||
        check(bingham_ahrs_new(&p, &c), "bingham_ahrs_new"))
        return 1;

    double q[4] = {cos(0.4), 0.0, 0.0, sin(0.4)}; /* truth: heading 46 deg to start */

    /* C's wrong start: flip = (0, 1, 0, 0) (+) truth, i.e. 180 deg about east, 10 deg spread */
    double m0[16], z0[4], mc[16], zc[4], wrong[4];
    const double flip[4] = {0.0, 1.0, 0.0, 0.0};
    qmul(flip, q, wrong);
    if (check(bingham_noise_from_angle_std(4, 10.0 / DEG, m0, z0), "bingham_noise_from_angle_std") ||
        check(bingham_rotate_left(4, m0, z0, wrong, mc, zc), "bingham_rotate_left") ||
        check(bingham_ahrs_set_state(c, mc, zc), "bingham_ahrs_set_state"))
        return 1;
    double recovered_c = 0.0; /* from then on C stays within 5 deg of the truth */
    double sum_a = 0, sum_b = 0;
    int cnt_a = 0, cnt_b = 0;
    const char *v = getenv("BINGHAM_VERBOSE");
    const int every = (int)((v && *v && strcmp(v, "0") != 0 ? 5 : 15) * RATE); /* samples per row */
    printf("The AHRS on a simulated IMU (60 s at 200 Hz, known truth): A from t = 0, B from t = %.0f s\n"
           "  in fast motion, C from a start 180 deg wrong. err = angle to the truth, spread = the\n"
           "  AHRS's own predicted RMS error, bias err = error of A's gyroscope-bias estimate.\n",
           START_B);
    printf("  time   err A   spread A   err B   spread B   err C   bias err A\n");
    printf("   (s)   (deg)     (deg)    (deg)     (deg)    (deg)     (deg/s)\n");
    for (int k = 1; k <= n; ++k) {
        double t = k * dt, w0[3], w1[3], w[3];
        /* propagate the truth with the midpoint rate over the step: q <- q (+) exp(w dt / 2) */
        true_rate(t - dt, w0);
        true_rate(t, w1);
        for (int i = 0; i < 3; ++i) w[i] = 0.5 * (w0[i] + w1[i]);
        double wn = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]), h = 0.5 * wn * dt;
        double s = wn > 0 ? sin(h) / wn : 0.0, dq[4] = {cos(h), s * w[0], s * w[1], s * w[2]};
        qmul(q, dq, q);

        /* sensors */
        double gyr[3], acc[3], mag[3], f_world[3], m_world[3];
        int burst = t > 7.0 && fmod(t, 7.0) < 0.3;
        double disturb = t >= 30.0 && t < 35.0 ? 1.3 : 1.0;
        for (int i = 0; i < 3; ++i) {
            gyr[i] = w1[i] + bias[i] + 0.003 * gauss();
            f_world[i] = g_up[i] + (burst && i == 0 ? 5.0 : 0.0);
            m_world[i] = disturb * field[i];
        }
        to_sensor(q, f_world, acc);
        to_sensor(q, m_world, mag);
        for (int i = 0; i < 3; ++i) acc[i] += 0.05 * gauss(), mag[i] += 0.3 * gauss();

        if (check(bingham_ahrs_update(a, gyr, acc, mag), "bingham_ahrs_update (A)")) return 1;
        if (k >= start_b && check(bingham_ahrs_update(b, gyr, acc, mag), "bingham_ahrs_update (B)")) return 1;
        if (check(bingham_ahrs_update(c, gyr, acc, mag), "bingham_ahrs_update (C)")) return 1;
        double qa[4], qb[4], qc[4];
        bingham_ahrs_quaternion(a, qa);
        bingham_ahrs_quaternion(b, qb);
        bingham_ahrs_quaternion(c, qc);
        double ea = angle_between(q, qa), eb = k >= start_b ? angle_between(q, qb) : NAN;
        double ec = angle_between(q, qc);
        if (k == 1) printf("%6.3f %7.2f %9s  %7s %9s  %7.2f   (C's wrong start)\n", t, ea, "", "", "", ec);
        if (ec >= 5.0) recovered_c = t + dt;
        if (t > 10.0) sum_a += ea * ea, ++cnt_a;
        if (t > START_B + 10.0) sum_b += eb * eb, ++cnt_b;

        if (k % every == 0) {
            double sa[4], sb[4] = {0, 0, 0, NAN}, be[3];
            bingham_ahrs_angular_spread(a, sa);
            if (k >= start_b) bingham_ahrs_angular_spread(b, sb);
            bingham_ahrs_gyro_bias(a, be);
            double dbx = be[0] - bias[0], dby = be[1] - bias[1], dbz = be[2] - bias[2];
            char b_err[16] = "      -", b_spread[16] = "        -"; /* B has not started */
            if (k >= start_b) {
                snprintf(b_err, sizeof b_err, "%7.2f", eb);
                snprintf(b_spread, sizeof b_spread, "%9.2f", sb[3] * DEG);
            }
            printf("%6.1f %7.2f %9.2f  %s %s  %7.2f   %10.3f\n", t, ea, sa[3] * DEG, b_err, b_spread, ec,
                   sqrt(dbx * dbx + dby * dby + dbz * dbz) * DEG);
        }
    }
    printf("RMS error after settling: A %.2f deg (t > 10 s), B %.2f deg (t > %.0f s)\n", sqrt(sum_a / cnt_a),
           sqrt(sum_b / cnt_b), START_B + 10.0);
    printf("C (started 180 deg wrong) within 5 deg of the truth from t = %.2f s on\n", recovered_c);
    bingham_ahrs_free(a);
    bingham_ahrs_free(b);
    bingham_ahrs_free(c);
    return 0;
}
