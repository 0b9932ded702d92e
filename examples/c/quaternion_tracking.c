/* Orientation tracking with unit quaternions and the recursive Bingham filter (d = 4): the
 * evaluation scenario of Kurz et al., "Recursive Bingham Filter for Directional Estimation
 * Involving 180 Degree Symmetry", JAIF 2014, Sec. 7.2, against the Kalman filter adapted as in
 * Sec. 7.
 *
 *   usage: quaternion_tracking [run.csv]
 *
 * Quaternions are scalar first, (w, x, y, z); q and -q are the same rotation, which the
 * antipodally symmetric Bingham distribution models exactly. Composition is the Hamilton
 * product. The true orientation performs a random walk x[k] = x[k-1] (+) w[k-1] and is measured
 * as z[k] = x[k] (+) v[k]:
 *
 *   initial estimate   M0 = I,                  z0 = (-1, -1, -1, 0)        (mode (0, 0, 0, 1))
 *   system noise       Mw = anti-diagonal ones, zw = (-200, -200, -2, 0)    (mode (1, 0, 0, 0))
 *   measurement noise  Mv = anti-diagonal ones, zv = (-500, -500, -500, 0)  (mode (1, 0, 0, 0))
 *   true initial state (0, 1, 0, 0); 100 steps; 100 Monte Carlo runs.
 *
 * The system noise is far from isotropic: with z = -2 along (0, 1, 0, 0) it mostly turns the
 * object about its x axis. Noise is drawn with the library's exact sampler (bingham_sample;
 * run r uses the seeds 1000 + 2r and 1001 + 2r, as testkit/src/scenarios.rs, so the Rust test
 * suite reproduces these numbers). Error per step: e = min(angle, pi - angle) between truth and
 * estimate as vectors in R^4 (half the rotation angle between the orientations); per run the
 * RMSE over the steps.
 *
 * The Kalman filter (JAIF Sec. 7) works on the quaternion as a vector in R^4 with identity
 * system and measurement models; its covariances are Gaussians fitted to one mode of each
 * Bingham density (C = E[(s x - mu)(s x - mu)^T], mu the mode, s = sign(mu^T x), here by Monte
 * Carlo with 100000 samples of the library's sampler); the measurement is mirrored (z <- -z)
 * when it is more than 90 degrees from the prediction, and the estimate is normalized after
 * each update.
 *
 * With a file name, run 0 is written as CSV: step, the true quaternion, the Bingham filter's
 * mode, the Kalman estimate (each sign-aligned with the truth) and both errors (radians).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "bingham.h"

#define D 4
#define STEPS 100
#define RUNS 100
#define FIT_SAMPLES 100000

static const double PI = 3.14159265358979323846;

static void check(bingham_status st, const char *what) {
    if (st != BINGHAM_OK) {
        char msg[512];
        bingham_last_error_message(msg, sizeof msg, NULL);
        fprintf(stderr, "%s failed: %s (%s)\n", what, bingham_status_str((int)st), msg);
        exit(1);
    }
}

/* ---- scenario ------------------------------------------------------------------------------ */

static const double M0[D * D] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
static const double Z0[D] = {-1, -1, -1, 0};
static const double MW[D * D] = {0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 0};
static const double ZW[D] = {-200, -200, -2, 0};
static const double MV[D * D] = {0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 0};
static const double ZV[D] = {-500, -500, -500, 0};
static const double X0[D] = {0, 1, 0, 0};

/* Hamilton product, scalar first, normalized */
static void qmul(const double *a, const double *b, double *out) {
    double r[D], n;
    int i;
    r[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    r[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    r[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    r[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
    n = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3]);
    for (i = 0; i < D; ++i) out[i] = r[i] / n;
}

static double dot(const double *a, const double *b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
}

/* axial error: min(angle, pi - angle) */
static double axial_error(const double *a, const double *b) {
    double c = fabs(dot(a, b)) / sqrt(dot(a, a) * dot(b, b));
    return acos(c > 1 ? 1 : c);
}

/* ---- Kalman filter ------------------------------------------------------------------------- */

/* The Gaussian fitted to one mode of Bingham(m, z): mu = the mode,
 * C = E[(s x - mu)(s x - mu)^T], s = sign(mu^T x), by Monte Carlo. */
static void gaussian_fit(const double *m, const double *z, uint64_t seed, double *mu, double *c) {
    double *x = malloc(sizeof(double) * FIT_SAMPLES * D);
    int i, a, b;
    if (!x) {
        fprintf(stderr, "out of memory\n");
        exit(1);
    }
    check(bingham_mode(D, m, z, mu), "bingham_mode");
    check(bingham_sample(D, m, z, seed, FIT_SAMPLES, x), "bingham_sample");
    for (a = 0; a < D * D; ++a) c[a] = 0;
    for (i = 0; i < FIT_SAMPLES; ++i) {
        double *xi = x + D * i, s = dot(mu, xi) < 0 ? -1 : 1, e[D];
        for (a = 0; a < D; ++a) e[a] = s * xi[a] - mu[a];
        for (a = 0; a < D; ++a)
            for (b = 0; b < D; ++b) c[a * D + b] += e[a] * e[b] / FIT_SAMPLES;
    }
    free(x);
}

typedef struct {
    double x[D], p[D * D];
} kalman;

static double kq[D * D], kr[D * D], kmu_w[D];

static void kalman_predict(kalman *k) {
    int i;
    qmul(k->x, kmu_w, k->x); /* the identity here: the noise mode is (1, 0, 0, 0) */
    for (i = 0; i < D * D; ++i) k->p[i] += kq[i];
}

/* Solves S X = B for symmetric positive definite S (Cholesky), B and X D x D row-major. */
static void spd_solve(const double *s, const double *bm, double *x) {
    double l[D * D] = {0};
    int i, j, k, col;
    for (j = 0; j < D; ++j) {
        double t = s[j * D + j];
        for (k = 0; k < j; ++k) t -= l[j * D + k] * l[j * D + k];
        l[j * D + j] = sqrt(t);
        for (i = j + 1; i < D; ++i) {
            double u = s[i * D + j];
            for (k = 0; k < j; ++k) u -= l[i * D + k] * l[j * D + k];
            l[i * D + j] = u / l[j * D + j];
        }
    }
    for (col = 0; col < D; ++col) {
        double y[D];
        for (i = 0; i < D; ++i) {
            double t = bm[i * D + col];
            for (k = 0; k < i; ++k) t -= l[i * D + k] * y[k];
            y[i] = t / l[i * D + i];
        }
        for (i = D - 1; i >= 0; --i) {
            double t = y[i];
            for (k = i + 1; k < D; ++k) t -= l[k * D + i] * x[k * D + col];
            x[i * D + col] = t / l[i * D + i];
        }
    }
}

static void kalman_update(kalman *k, const double *zm) {
    double z[D], s[D * D], kt[D * D], p[D * D], r[D], n;
    int i, j, l;
    double sgn = dot(zm, k->x) < 0 ? -1 : 1; /* mirror the measurement */
    for (i = 0; i < D; ++i) z[i] = sgn * zm[i];
    for (i = 0; i < D * D; ++i) s[i] = k->p[i] + kr[i];
    spd_solve(s, k->p, kt); /* K^T = S^-1 P, as P and S are symmetric */
    for (i = 0; i < D; ++i) r[i] = z[i] - k->x[i];
    for (i = 0; i < D; ++i)
        for (j = 0; j < D; ++j) k->x[i] += kt[j * D + i] * r[j];
    for (i = 0; i < D; ++i)
        for (j = 0; j < D; ++j) {
            p[i * D + j] = k->p[i * D + j];
            for (l = 0; l < D; ++l) p[i * D + j] -= kt[l * D + i] * k->p[l * D + j];
        }
    for (i = 0; i < D; ++i)
        for (j = 0; j < D; ++j) k->p[i * D + j] = 0.5 * (p[i * D + j] + p[j * D + i]);
    n = sqrt(dot(k->x, k->x));
    for (i = 0; i < D; ++i) k->x[i] /= n;
}

/* ---- main ---------------------------------------------------------------------------------- */

int main(int argc, char **argv) {
    double mu0[D], c0[D * D], mu_v[D];
    double sum_b = 0, sum_k = 0, sq_b = 0, sq_k = 0, err_time_b[STEPS] = {0},
           err_time_k[STEPS] = {0};
    double filter_seconds = 0;
    int wins = 0, r, k, i;
    FILE *csv = NULL;

    if (argc > 2) {
        fprintf(stderr, "usage: %s [run.csv]\n", argv[0]);
        return 2;
    }
    if (argc == 2) {
        csv = fopen(argv[1], "w");
        if (!csv) {
            perror(argv[1]);
            return 1;
        }
        fprintf(csv, "step,truth_w,truth_x,truth_y,truth_z,bingham_w,bingham_x,bingham_y,"
                     "bingham_z,kalman_w,kalman_x,kalman_y,kalman_z,error_bingham,error_kalman\n");
    }

    gaussian_fit(M0, Z0, 7, mu0, c0);
    gaussian_fit(MW, ZW, 8, kmu_w, kq);
    gaussian_fit(MV, ZV, 9, mu_v, kr);
    printf("Quaternion tracking (d = 4, JAIF Sec. 7.2), Bingham vs Kalman filter: %d Monte Carlo runs of %d "
           "steps\n",
           RUNS, STEPS);
    printf("  Kalman covariances (Gaussian fit to one mode, diagonals): C0 = (%.2g %.2g %.2g %.2g)"
           "\n    Cw = (%.2g %.2g %.2g %.2g)  Cv = (%.2g %.2g %.2g %.2g)\n",
           c0[0], c0[5], c0[10], c0[15], kq[0], kq[5], kq[10], kq[15], kr[0], kr[5], kr[10],
           kr[15]);

    for (r = 0; r < RUNS; ++r) {
        double w[STEPS * D], v[STEPS * D], xs[STEPS * D], zs[STEPS * D], modes[STEPS * D],
            x[D], mb = 0, mk = 0;
        bingham_filter *f = NULL;
        kalman kf;
        clock_t t0;
        check(bingham_sample(D, MW, ZW, 1000 + 2 * (uint64_t)r, STEPS, w), "bingham_sample");
        check(bingham_sample(D, MV, ZV, 1001 + 2 * (uint64_t)r, STEPS, v), "bingham_sample");
        /* simulate: x[k] = x[k-1] (+) w[k-1], z[k] = x[k] (+) v[k] */
        for (i = 0; i < D; ++i) x[i] = X0[i];
        for (k = 0; k < STEPS; ++k) {
            qmul(x, w + D * k, x);
            qmul(x, v + D * k, zs + D * k);
            for (i = 0; i < D; ++i) xs[D * k + i] = x[i];
        }
        /* the Bingham filter */
        check(bingham_filter_new(D, M0, Z0, &f), "bingham_filter_new");
        t0 = clock();
        for (k = 0; k < STEPS; ++k) {
            check(bingham_filter_predict(f, MW, ZW), "bingham_filter_predict");
            check(bingham_filter_update(f, zs + D * k, MV, ZV), "bingham_filter_update");
            check(bingham_filter_mode(f, modes + D * k), "bingham_filter_mode");
        }
        filter_seconds += (double)(clock() - t0) / CLOCKS_PER_SEC;
        bingham_filter_free(f);
        /* the Kalman filter, and the errors */
        for (i = 0; i < D; ++i) kf.x[i] = mu0[i];
        for (i = 0; i < D * D; ++i) kf.p[i] = c0[i];
        for (k = 0; k < STEPS; ++k) {
            const double *xk = xs + D * k, *mode = modes + D * k;
            double eb, ek;
            kalman_predict(&kf);
            kalman_update(&kf, zs + D * k);
            eb = axial_error(xk, mode);
            ek = axial_error(xk, kf.x);
            mb += eb * eb;
            mk += ek * ek;
            err_time_b[k] += eb / RUNS;
            err_time_k[k] += ek / RUNS;
            if (csv && r == 0) {
                double sb = dot(mode, xk) < 0 ? -1 : 1, sk = dot(kf.x, xk) < 0 ? -1 : 1;
                fprintf(csv, "%d", k + 1);
                for (i = 0; i < D; ++i) fprintf(csv, ",%.9f", xk[i]);
                for (i = 0; i < D; ++i) fprintf(csv, ",%.9f", sb * mode[i]);
                for (i = 0; i < D; ++i) fprintf(csv, ",%.9f", sk * kf.x[i]);
                fprintf(csv, ",%.9f,%.9f\n", eb, ek);
            }
        }
        mb = sqrt(mb / STEPS);
        mk = sqrt(mk / STEPS);
        sum_b += mb;
        sum_k += mk;
        sq_b += mb * mb;
        sq_k += mk * mk;
        if (mb < mk) ++wins;
    }
    if (csv) fclose(csv);

    {
        double mb = sum_b / RUNS, mk = sum_k / RUNS;
        double sb = sqrt((sq_b / RUNS - mb * mb) / (RUNS - 1)),
               sk = sqrt((sq_k / RUNS - mk * mk) / (RUNS - 1));
        printf("  mean RMSE  Bingham filter %.4f rad (%.2f deg) +- %.4f rad (standard error)\n", mb, mb * 180 / PI, sb);
        printf("             Kalman filter  %.4f rad (%.2f deg) +- %.4f rad\n", mk, mk * 180 / PI, sk);
        printf("  Bingham filter better in %d of %d runs (%d %%), Kalman in %d (%d %%)\n", wins,
               RUNS, 100 * wins / RUNS, RUNS - wins, 100 * (RUNS - wins) / RUNS);
        printf("  mean error at steps 1, 5, 20, 100: Bingham %.3f %.3f %.3f %.3f, "
               "Kalman %.3f %.3f %.3f %.3f rad\n",
               err_time_b[0], err_time_b[4], err_time_b[19], err_time_b[99], err_time_k[0],
               err_time_k[4], err_time_k[19], err_time_k[99]);
        printf("  Bingham filter: %.2f us per step (predict + update)\n",
               1e6 * filter_seconds / (RUNS * STEPS));
        if (argc == 2) printf("  run 0 written to %s\n", argv[1]);
    }
    return 0;
}
