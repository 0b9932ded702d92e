/* Axis tracking in the plane with the recursive Bingham filter (d = 2): the evaluation scenario
 * of Kurz et al., "Recursive Bingham Filter for Directional Estimation Involving 180 Degree
 * Symmetry", JAIF 2014, Sec. 7.1, against the Kalman filter adapted as in Sec. 7.
 *
 *   usage: axis_tracking [run.csv]
 *
 * An axis (180-degree symmetric: the angles a and a + pi are the same axis) is represented by the
 * unit vector (cos a, sin a); composition is complex multiplication. The truth performs a random
 * walk x[k] = x[k-1] (+) w[k-1] and is measured as z[k] = x[k] (+) v[k]:
 *
 *   initial estimate   M0 = I,            z0 = (-1, 0)     (mode (0, 1): 90 degrees off)
 *   system noise       Mw = [[0,1],[1,0]], zw = (-200, 0)   (mode (1, 0), about 2.9 degrees)
 *   measurement noise  Mv = [[0,1],[1,0]], zv = (-2, 0)     (mode (1, 0), about 36 degrees)
 *   true initial state (1, 0); 100 steps; 100 Monte Carlo runs.
 *
 * The noise is drawn with the library's exact sampler (bingham_sample, fixed seeds: run r uses
 * the seeds 1000 + 2r and 1001 + 2r, as testkit/src/scenarios.rs does, so the Rust test
 * suite reproduces these numbers). Error per step: the axial angle between truth and estimate,
 * e = min(angle, pi - angle); per run the RMSE over the steps.
 *
 * The Kalman filter (JAIF Sec. 7) works on the vector in R^2 with identity system and
 * measurement models; its covariances are Gaussians fitted to one mode of each Bingham density
 * by numerical integration (JAIF eq. 57); the measurement is mirrored (z <- -z) when it is more
 * than 90 degrees from the prediction, and the estimate is normalized after each update.
 *
 * With a file name, one run (run 0) is written as CSV: step, truth angle, measurement angle,
 * Bingham mode angle, the bounds of its 95 % interval (from the von Mises form of the d = 2
 * Bingham density, JAIF App. B: a Bingham with z = (z1, 0) is a von Mises density in the doubled
 * angle with kappa = -z1/2; the interval is found numerically) and the Kalman estimate's angle.
 * All angles in radians, each axis angle shifted by a multiple of pi to lie within pi/2 of the
 * truth (so the curves are continuous). scripts/plot_run.py draws it.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "bingham.h"

#define D 2
#define STEPS 100
#define RUNS 100

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

static const double M0[D * D] = {1, 0, 0, 1};
static const double Z0[D] = {-1, 0};
static const double MW[D * D] = {0, 1, 1, 0};
static const double ZW[D] = {-200, 0};
static const double MV[D * D] = {0, 1, 1, 0};
static const double ZV[D] = {-2, 0};
static const double X0[D] = {1, 0};

/* complex multiplication (re, im) */
static void cmul(const double *a, const double *b, double *out) {
    double re = a[0] * b[0] - a[1] * b[1];
    double im = a[0] * b[1] + a[1] * b[0];
    double n = sqrt(re * re + im * im);
    out[0] = re / n;
    out[1] = im / n;
}

/* axial error: min(angle, pi - angle) between two axes */
static double axial_error(const double *a, const double *b) {
    double c = fabs(a[0] * b[0] + a[1] * b[1]) /
               sqrt((a[0] * a[0] + a[1] * a[1]) * (b[0] * b[0] + b[1] * b[1]));
    return acos(c > 1 ? 1 : c);
}

/* ---- Kalman filter ------------------------------------------------------------------------- */

/* The Gaussian fitted to one mode of Bingham(m, z) (JAIF eq. 57): mean mu = the mode,
 * C = int_{alpha-pi/2}^{alpha+pi/2} f(phi) (x - mu)(x - mu)^T dphi / int f over the same half
 * circle, with x = (cos phi, sin phi), by the midpoint rule (the integrand is smooth and the
 * density is negligible at the ends for the scenario's noises; a small remainder at the ends is
 * periodic). */
static void gaussian_fit(const double *m, const double *z, double *mu, double *c) {
    enum { N = 20000 };
    static double x[N * D], p[N];
    double alpha, mass = 0;
    int i;
    check(bingham_mode(D, m, z, mu), "bingham_mode");
    alpha = atan2(mu[1], mu[0]);
    for (i = 0; i < N; ++i) {
        double phi = alpha - PI / 2 + PI * (i + 0.5) / N;
        x[2 * i] = cos(phi);
        x[2 * i + 1] = sin(phi);
    }
    check(bingham_pdf(D, m, z, N, x, p), "bingham_pdf");
    c[0] = c[1] = c[2] = c[3] = 0;
    for (i = 0; i < N; ++i) {
        double e0 = x[2 * i] - mu[0], e1 = x[2 * i + 1] - mu[1];
        mass += p[i];
        c[0] += p[i] * e0 * e0;
        c[1] += p[i] * e0 * e1;
        c[3] += p[i] * e1 * e1;
    }
    c[0] /= mass;
    c[1] /= mass;
    c[3] /= mass;
    c[2] = c[1];
}

typedef struct {
    double x[D], p[D * D];
} kalman;

static double kq[D * D], kr[D * D], kmu_w[D];

static void kalman_predict(kalman *k) {
    int i;
    cmul(k->x, kmu_w, k->x); /* identity here: the noise mode is (1, 0) */
    for (i = 0; i < D * D; ++i) k->p[i] += kq[i];
}

static void kalman_update(kalman *k, const double *zm) {
    double z[D], s[D * D], si[D * D], g[D * D], det, r0, r1, p[D * D], n;
    int i, j, l;
    double sgn = (zm[0] * k->x[0] + zm[1] * k->x[1] < 0) ? -1 : 1; /* mirror the measurement */
    z[0] = sgn * zm[0];
    z[1] = sgn * zm[1];
    for (i = 0; i < D * D; ++i) s[i] = k->p[i] + kr[i];
    det = s[0] * s[3] - s[1] * s[2];
    si[0] = s[3] / det;
    si[1] = -s[1] / det;
    si[2] = -s[2] / det;
    si[3] = s[0] / det;
    for (i = 0; i < D; ++i)
        for (j = 0; j < D; ++j) {
            g[i * D + j] = 0;
            for (l = 0; l < D; ++l) g[i * D + j] += k->p[i * D + l] * si[l * D + j];
        }
    r0 = z[0] - k->x[0];
    r1 = z[1] - k->x[1];
    k->x[0] += g[0] * r0 + g[1] * r1;
    k->x[1] += g[2] * r0 + g[3] * r1;
    for (i = 0; i < D; ++i)
        for (j = 0; j < D; ++j) {
            p[i * D + j] = k->p[i * D + j];
            for (l = 0; l < D; ++l) p[i * D + j] -= g[i * D + l] * k->p[l * D + j];
        }
    k->p[0] = p[0];
    k->p[3] = p[3];
    k->p[1] = k->p[2] = 0.5 * (p[1] + p[2]);
    n = sqrt(k->x[0] * k->x[0] + k->x[1] * k->x[1]);
    k->x[0] /= n;
    k->x[1] /= n;
}

/* ---- 95 % interval of a d = 2 Bingham density -------------------------------------------- */

/* P(|phi| <= delta) for the von Mises density prop. to exp(kappa cos phi) on [-pi, pi]
 * (Simpson's rule on exp(kappa (cos phi - 1)), which does not overflow). */
static double vm_mass(double kappa, double delta) {
    enum { N = 2000 };
    double a = 0, t = 0;
    int i;
    for (i = 0; i <= N; ++i) {
        double w = (i == 0 || i == N) ? 1 : (i % 2 ? 4 : 2);
        a += w * exp(kappa * (cos(delta * i / N) - 1));
        t += w * exp(kappa * (cos(PI * i / N) - 1));
    }
    return (a * delta) / (t * PI);
}

/* Half-width (in the axis angle) of the central 95 % interval of Bingham(M, (z1, 0)). */
static double half_width_95(double z1) {
    double kappa = -z1 / 2, lo = 0, hi = PI;
    int it;
    for (it = 0; it < 60; ++it) {
        double mid = 0.5 * (lo + hi);
        if (vm_mass(kappa, mid) < 0.95)
            lo = mid;
        else
            hi = mid;
    }
    return 0.25 * (lo + hi); /* the doubled angle phi = 2 theta */
}

/* the representative of the axis angle a (mod pi) nearest to ref */
static double near(double a, double ref) { return a + PI * floor((ref - a) / PI + 0.5); }

/* ---- main ---------------------------------------------------------------------------------- */

int main(int argc, char **argv) {
    double mu0[D], c0[D * D];
    double sum_b = 0, sum_k = 0, sq_b = 0, sq_k = 0, err_time_b[STEPS] = {0},
           err_time_k[STEPS] = {0};
    double filter_seconds = 0;
    int wins = 0, r, k;
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
        fprintf(csv, "step,truth,measurement,bingham_mode,bingham_lo95,bingham_hi95,kalman\n");
    }

    gaussian_fit(M0, Z0, mu0, c0);
    gaussian_fit(MW, ZW, kmu_w, kq);
    {
        double mu_v[D];
        gaussian_fit(MV, ZV, mu_v, kr);
    }
    printf("Axis tracking (d = 2, JAIF Sec. 7.1), Bingham vs Kalman filter: %d Monte Carlo runs of %d steps\n", RUNS,
           STEPS);
    printf("  Kalman covariances (Gaussian fit to one mode, JAIF eq. 57; diagonals): C0 = (%.2g %.2g)  "
           "Cw = (%.2g %.2g)  Cv = (%.2g %.2g)\n",
           c0[0], c0[3], kq[0], kq[3], kr[0], kr[3]);

    for (r = 0; r < RUNS; ++r) {
        double w[STEPS * D], v[STEPS * D], xs[STEPS * D], zs[STEPS * D], modes[STEPS * D],
            z1[STEPS], x[D], mb = 0, mk = 0, truth_angle = 0;
        bingham_filter *f = NULL;
        kalman kf;
        clock_t t0;
        check(bingham_sample(D, MW, ZW, 1000 + 2 * (uint64_t)r, STEPS, w), "bingham_sample");
        check(bingham_sample(D, MV, ZV, 1001 + 2 * (uint64_t)r, STEPS, v), "bingham_sample");
        /* simulate: x[k] = x[k-1] (+) w[k-1], z[k] = x[k] (+) v[k] */
        x[0] = X0[0];
        x[1] = X0[1];
        for (k = 0; k < STEPS; ++k) {
            cmul(x, w + D * k, x);
            cmul(x, v + D * k, zs + D * k);
            xs[D * k] = x[0];
            xs[D * k + 1] = x[1];
        }
        /* the Bingham filter */
        check(bingham_filter_new(D, M0, Z0, &f), "bingham_filter_new");
        t0 = clock();
        for (k = 0; k < STEPS; ++k) {
            double m[D * D], z[D];
            check(bingham_filter_predict(f, MW, ZW), "bingham_filter_predict");
            check(bingham_filter_update(f, zs + D * k, MV, ZV), "bingham_filter_update");
            check(bingham_filter_get_state(f, m, z), "bingham_filter_get_state");
            modes[D * k] = m[1];     /* the mode: last column of the row-major M */
            modes[D * k + 1] = m[3];
            z1[k] = z[0];
        }
        filter_seconds += (double)(clock() - t0) / CLOCKS_PER_SEC;
        bingham_filter_free(f);
        /* the Kalman filter, and the errors */
        kf.x[0] = mu0[0];
        kf.x[1] = mu0[1];
        for (k = 0; k < D * D; ++k) kf.p[k] = c0[k];
        for (k = 0; k < STEPS; ++k) {
            const double *xk = xs + D * k, *zk = zs + D * k, *mode = modes + D * k;
            double eb, ek;
            kalman_predict(&kf);
            kalman_update(&kf, zk);
            eb = axial_error(xk, mode);
            ek = axial_error(xk, kf.x);
            mb += eb * eb;
            mk += ek * ek;
            err_time_b[k] += eb / RUNS;
            err_time_k[k] += ek / RUNS;
            if (csv && r == 0) {
                double a_mode, hw;
                truth_angle = near(atan2(xk[1], xk[0]), truth_angle);
                a_mode = near(atan2(mode[1], mode[0]), truth_angle);
                hw = half_width_95(z1[k]);
                fprintf(csv, "%d,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f\n", k + 1, truth_angle,
                        near(atan2(zk[1], zk[0]), truth_angle), a_mode, a_mode - hw, a_mode + hw,
                        near(atan2(kf.x[1], kf.x[0]), truth_angle));
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
