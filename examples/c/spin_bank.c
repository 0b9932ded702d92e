/* Which way is it spinning? One spin filter against a bank of them (Glover & Kaelbling 2013).
 *
 * An object (think of a ball with a logo) spins at a constant rate, one of 12 spin types: 4 axes
 * x 3 rates (45, 67.5, 90 degrees per frame). A camera sees its orientation every frame through
 * Bingham noise with concentrations (-40, -40, -10), except every 4th frame (the logo faces
 * away: no observation), and cannot tell the logo from its 180-degree turn about the body's z
 * axis: each detection has two readings, y and y o flip, and each filter takes the one with the
 * higher predictive likelihood.
 *
 * - QBF-2: one spin filter with a broad spin prior at "no spin", concentrations (-3, -3, -3).
 * - The bank: one spin filter per spin type, its prior centred there ((-50)^3). Every frame each
 *   member adds its predictive log-likelihood of the observation to a running sum; the bank's
 *   answer is the member with the largest sum (on frame 1 all tie: with a uniform orientation
 *   prior one observation says nothing about the spin).
 *
 * The bank is an example, not library API: it is a loop over handles and a running sum of
 * bingham_spin_filter_log_likelihood(); which priors, MAP or mixture weights, pruning and
 * resetting are the application's choices. Quaternions are scalar first (w, x, y, z), and
 * q o r = qmul(q, r) rotates by r, then by q. Output: frames 1, 2, 5, 10, 20, 40 of one trajectory
 * (BINGHAM_VERBOSE=1: frames 1 to 6 and every 5th), then the
 * summary of 24 trajectories (2 of each spin type; the spin error's median and worst case: a
 * single filter now and then locks onto a wrong spin in the first frames, while the readings
 * are still ambiguous, and keeps it; the bank's summed likelihoods rule that out).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bingham.h"

#define TYPES 12
#define FRAMES 40
#define TRIALS 24
#define SHOW 7 /* the trajectory printed frame by frame */
static const double PI = 3.14159265358979323846;
#define R3 0.5773502691896258 /* 1 / sqrt(3) */
static const double AXES[4][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {R3, R3, R3}};
static const char *AXIS_NAMES[4] = {"x", "y", "z", "xyz"};
static const double RATES_DEG[3] = {45, 67.5, 90};

static void check(bingham_status st, const char *what) {
    char msg[512];
    if (st == BINGHAM_OK) return;
    bingham_last_error_message(msg, sizeof msg, NULL);
    fprintf(stderr, "%s failed: %s\n", what, msg);
    exit(1);
}

/* Hamilton product q r, scalar first */
static void qmul(const double *a, const double *b, double *out) {
    double r[4];
    r[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    r[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    r[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    r[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
    out[0] = r[0], out[1] = r[1], out[2] = r[2], out[3] = r[3];
}

/* spin type k: the rotation by RATES_DEG[k % 3] about AXES[k / 3] */
static void spin_type(int k, double *q) {
    double half = RATES_DEG[k % 3] * PI / 360, s = sin(half);
    q[0] = cos(half), q[1] = s * AXES[k / 3][0], q[2] = s * AXES[k / 3][1], q[3] = s * AXES[k / 3][2];
}

/* the rotation angle between two rotations, degrees */
static double angle_deg(const double *a, const double *b) {
    double c = fabs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]);
    return 2 * acos(c > 1 ? 1 : c) * 180 / PI;
}

/* Bingham(M, z) with mode q and concentration -lambda about it: M's columns q o e1, q o e2,
   q o e3 and q itself last (row-major) */
static void centred(const double *q, double lambda, double *m, double *z) {
    int i, j;
    for (j = 0; j < 4; ++j) {
        double e[4] = {0, 0, 0, 0}, col[4];
        e[(j + 1) % 4] = 1;
        qmul(q, e, col);
        for (i = 0; i < 4; ++i) m[4 * i + j] = col[i];
        z[j] = j == 3 ? 0 : -lambda;
    }
}

/* The reading (y or y_flip) the filter finds more probable; adds its log-likelihood to *sum. */
static const double *pick(const bingham_spin_filter *f, const double *y, const double *y_flip, const double *mo,
                          const double *zo, double *sum) {
    double l1, l2;
    check(bingham_spin_filter_log_likelihood(f, y, mo, zo, &l1), "log_likelihood");
    check(bingham_spin_filter_log_likelihood(f, y_flip, mo, zo, &l2), "log_likelihood");
    *sum += l1 >= l2 ? l1 : l2;
    return l1 >= l2 ? y : y_flip;
}

static int by_value(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(void) {
    static const double FLIP[4] = {0, 0, 0, 1}; /* 180 degrees about the body z axis */
    double eye[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}, uniform[4] = {0, 0, 0, 0};
    double none[4] = {1, 0, 0, 0}, mw[16], zw[4], mb[16], zb[4], mo[16], zo[4];
    double mp[TYPES][16], zp[TYPES][4];
    int correct[3] = {0, 0, 0};
    double err_single[TRIALS], err_bank[TRIALS];
    int trial, k;
    const char *v_env = getenv("BINGHAM_VERBOSE");
    const int verbose = v_env && *v_env && strcmp(v_env, "0") != 0;

    /* noises: on the spin (-400)^3 at the identity, on the observation (-40, -40, -10) */
    centred(none, 400, mw, zw);
    centred(none, 40, mo, zo);
    zo[2] = -10; /* less sure about the turn about the z axis */
    centred(none, 3, mb, zb); /* QBF-2's broad spin prior */
    for (k = 0; k < TYPES; ++k) {
        double q[4];
        spin_type(k, q);
        centred(q, 50, mp[k], zp[k]); /* the bank's priors */
    }

    printf("Which way is it spinning? One spin filter (QBF-2) vs a bank of %d, %d trajectories of %d frames\n",
           TYPES, TRIALS, FRAMES);
    for (trial = 0; trial < TRIALS; ++trial) {
        const int truth = trial % TYPES;
        double spin[4], x[4], noise[4 * FRAMES], sum[TYPES] = {0};
        bingham_spin_filter *single = NULL, *bank[TYPES];
        int frame, best;

        spin_type(truth, spin);
        check(bingham_sample(4, eye, uniform, 1000 + trial, 1, x), "sample"); /* a random start */
        check(bingham_sample(4, mo, zo, 2000 + trial, FRAMES, noise), "sample");
        /* a uniform orientation prior: nothing known about the orientation */
        check(bingham_spin_filter_new(eye, uniform, mb, zb, &single), "bingham_spin_filter_new");
        for (k = 0; k < TYPES; ++k) check(bingham_spin_filter_new(eye, uniform, mp[k], zp[k], &bank[k]), "new");
        if (trial == SHOW)
            printf("  one trajectory, true spin %s %.1f deg/frame (spin errors in deg/frame)\n"
                   "  frame  seen  QBF-2 error  bank pick  bank error\n",
                   AXIS_NAMES[truth / 3], RATES_DEG[truth % 3]);

        for (frame = 1; frame <= FRAMES; ++frame) {
            const int seen = frame % 4 != 0;
            double y[4], y_flip[4], ignored = 0, qs[4], qb[4];
            const double *reading;
            qmul(spin, x, x); /* the object turns */
            if (seen) {
                qmul(noise + 4 * (frame - 1), x, y); /* y = o o x */
                qmul(y, FLIP, y_flip);               /* the detector cannot tell y from y o flip */
            }
            reading = seen ? pick(single, y, y_flip, mo, zo, &ignored) : NULL; /* NULL: nothing seen */
            check(bingham_spin_filter_step(single, NULL, mw, zw, reading, mo, zo), "step");
            for (k = 0; k < TYPES; ++k) {
                reading = seen ? pick(bank[k], y, y_flip, mo, zo, &sum[k]) : NULL;
                check(bingham_spin_filter_step(bank[k], NULL, mw, zw, reading, mo, zo), "step");
            }
            for (best = 0, k = 1; k < TYPES; ++k)
                if (sum[k] > sum[best]) best = k; /* the bank's answer: the largest summed log-likelihood */
            check(bingham_spin_filter_spin_mode(single, qs), "spin_mode");
            check(bingham_spin_filter_spin_mode(bank[best], qb), "spin_mode");
            if (trial == SHOW && (verbose ? frame <= 6 || frame % 5 == 0
                                          : frame <= 2 || frame == 5 || frame == 10 || frame == 20 || frame == 40))
                printf("  %5d  %-4s  %11.1f  %5s %4.1f  %10.1f\n", frame, seen ? "yes" : "no", angle_deg(qs, spin),
                       AXIS_NAMES[best / 3], RATES_DEG[best % 3], angle_deg(qb, spin));
            if (frame == 10 || frame == 20 || frame == 40) correct[frame == 10 ? 0 : frame / 20] += best == truth;
            if (frame == FRAMES) err_single[trial] = angle_deg(qs, spin), err_bank[trial] = angle_deg(qb, spin);
        }
        bingham_spin_filter_free(single);
        for (k = 0; k < TYPES; ++k) bingham_spin_filter_free(bank[k]);
    }
    printf("  the bank picks the true spin type after 10 / 20 / 40 frames in %d / %d / %d of %d trajectories\n",
           correct[0],
           correct[1], correct[2], TRIALS);
    qsort(err_single, TRIALS, sizeof(double), by_value);
    qsort(err_bank, TRIALS, sizeof(double), by_value);
    printf("  spin error after %d frames, median / worst: QBF-2 %.1f / %.1f deg, bank %.1f / %.1f deg\n", FRAMES,
           (err_single[TRIALS / 2 - 1] + err_single[TRIALS / 2]) / 2, err_single[TRIALS - 1],
           (err_bank[TRIALS / 2 - 1] + err_bank[TRIALS / 2]) / 2, err_bank[TRIALS - 1]);
    return 0;
}
