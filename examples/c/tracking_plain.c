/* Tracking a spinning body with a gyroscope and absolute orientation fixes, with the C API.
 * The same program with the C++ wrapper and Eigen: examples/cpp/tracking_eigen.cpp (compare
 * the lengths; both print the same numbers).
 *
 * Truth: a body spinning at OMEGA rad/s (body frame), 100 Hz, 20 s. Gyroscope: each step's
 * increment exp(OMEGA dt / 2) times isotropic rotation noise of GYRO_DEG degrees; every 10th
 * step an orientation fix (a unit quaternion, scalar first) with FIX_DEG degrees of noise.
 * Noise is drawn with the library's sampler (bingham_sample) from the same Bingham
 * distributions the filter uses. Filter: predict with the gyroscope increment and isotropic noise
 * from an angle in degrees; update with each fix. Prints the RMS orientation error.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "bingham.h"

#define STEPS 2000
#define FIX_EVERY 10
static const double DT = 0.01, GYRO_DEG = 0.2, FIX_DEG = 3.0, INIT_DEG = 10.0;
static const double OMEGA[3] = {0.5, -0.3, 1.2};
static const double PI = 3.14159265358979323846;

static void check(bingham_status st, const char *what) {
    char msg[512];
    if (st == BINGHAM_OK) return;
    bingham_last_error_message(msg, sizeof msg, NULL);
    fprintf(stderr, "%s failed: %s\n", what, msg);
    exit(1);
}

/* Hamilton product, scalar first (w, x, y, z) */
static void qmul(const double *a, const double *b, double *out) {
    double r[4];
    r[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    r[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    r[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    r[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
    out[0] = r[0], out[1] = r[1], out[2] = r[2], out[3] = r[3];
}

/* the rotation by the rotation vector v (angle |v| about v / |v|) */
static void qexp(const double *v, double *q) {
    double angle = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]), s = sin(angle / 2) / angle;
    q[0] = cos(angle / 2), q[1] = s * v[0], q[2] = s * v[1], q[3] = s * v[2];
}

/* the rotation angle between two orientations, degrees */
static double angle_deg(const double *a, const double *b) {
    double c = fabs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]);
    return 2 * acos(c > 1 ? 1 : c) * 180 / PI;
}

int main(void) {
    double mw[16], zw[4], mv[16], zv[4], m0[16], z0[4], inc[4], truth[4] = {1, 0, 0, 0};
    double rot[3] = {OMEGA[0] * DT, OMEGA[1] * DT, OMEGA[2] * DT}, gyro[4], est[4], spread[4];
    double *gyro_noise = malloc(sizeof(double) * 4 * STEPS);
    double *fix_noise = malloc(sizeof(double) * 4 * (STEPS / FIX_EVERY));
    double sum_sq = 0;
    bingham_filter *f = NULL;
    int k;

    if (!gyro_noise || !fix_noise) return 1;
    check(bingham_noise_from_angle_std(4, GYRO_DEG * PI / 180, mw, zw), "process noise");
    check(bingham_noise_from_angle_std(4, FIX_DEG * PI / 180, mv, zv), "measurement noise");
    check(bingham_noise_from_angle_std(4, INIT_DEG * PI / 180, m0, z0), "initial state");
    check(bingham_sample(4, mw, zw, 1, STEPS, gyro_noise), "sample");
    check(bingham_sample(4, mv, zv, 2, STEPS / FIX_EVERY, fix_noise), "sample");
    check(bingham_filter_new(4, m0, z0, &f), "bingham_filter_new");
    qexp(rot, inc);
    for (k = 0; k < STEPS; ++k) {
        qmul(truth, inc, truth);
        qmul(inc, gyro_noise + 4 * k, gyro); /* the gyroscope's increment */
        check(bingham_filter_predict_rotation(f, gyro, mw, zw), "predict");
        if ((k + 1) % FIX_EVERY == 0) {
            double fix[4];
            qmul(truth, fix_noise + 4 * (k / FIX_EVERY), fix);
            check(bingham_filter_update(f, fix, mv, zv), "update");
        }
        check(bingham_filter_mode(f, est), "mode");
        sum_sq += angle_deg(truth, est) * angle_deg(truth, est);
    }
    check(bingham_filter_angular_spread(f, spread), "spread");
    printf("Gyroscope + fixes at 100 Hz, C API: RMS error %.3f deg over %d steps; final spread "
           "%.3f deg\n", sqrt(sum_sq / STEPS), STEPS, spread[3] * 180 / PI);
    bingham_filter_free(f);
    free(gyro_noise);
    free(fix_noise);
    return 0;
}
