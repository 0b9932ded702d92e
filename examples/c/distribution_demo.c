/* A tour of the distribution functions of the bingham C API (C99).
 *
 *   make demo          (builds the library, then compiles and runs this file)
 *   BINGHAM_VERBOSE=1  also prints the whole second-moment matrix
 *
 * or by hand, after `make install`:
 *
 *   cc -std=c99 distribution_demo.c $(pkg-config --cflags --libs bingham) -o demo
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bingham.h"

static const double PI = 3.14159265358979323846;

/* Every call returns a status; on failure print the library's message and stop. */
#define TRY(call)                                                                        \
    do {                                                                                 \
        bingham_status st_ = (call);                                                     \
        if (st_ != BINGHAM_OK) {                                                         \
            char msg_[512];                                                              \
            bingham_last_error_message(msg_, sizeof msg_, NULL);                         \
            fprintf(stderr, "%s failed: %s: %s\n", #call, bingham_status_str(st_), msg_); \
            exit(1);                                                                     \
        }                                                                                \
    } while (0)

static void print_matrix(const char *name, const double *a, size_t d) {
    printf("%s =\n", name);
    for (size_t i = 0; i < d; ++i) {
        printf("   ");
        for (size_t j = 0; j < d; ++j) printf(" %9.5f", a[i * d + j]);
        printf("\n");
    }
}

/* "name = (v0, v1, ...)" without a line end */
static void print_vector(const char *name, const double *v, size_t d) {
    printf("%s = (", name);
    for (size_t i = 0; i < d; ++i) printf("%s%.6g", i ? ", " : "", v[i]);
    printf(")");
}

int main(void) {
    const char *verbose = getenv("BINGHAM_VERBOSE");
    printf("The distribution functions on unit quaternions (w, x, y, z), d = 4 (bingham %s, header "
           "%d.%d.%d):\n",
           bingham_version(), BINGHAM_VERSION_MAJOR, BINGHAM_VERSION_MINOR, BINGHAM_VERSION_PATCH);

    /* 1. The normalization constant, exact, w.r.t. the surface measure: F(0) = |S^3| = 2 pi^2. */
    const double z0[4] = {0, 0, 0, 0};
    double f, df[4];
    TRY(bingham_normalization_constant(4, z0, &f, NULL));
    printf("  F(0) on S^3 = %.15f (2 pi^2 = %.15f)\n", f, 2 * PI * PI);

    /* z in any order and shift; the gradient comes back in the order of the input. */
    const double z[4] = {-20.0, -5.0, 0.0, -50.0};
    TRY(bingham_normalization_constant(4, z, &f, df));
    printf("  F(-20, -5, 0, -50) = %.15g, ", f);
    print_vector("dF/dz", df, 4);
    printf("\n");

    /* Very concentrated: F itself underflows, log F is fine. */
    const double zbig[4] = {-1e5, -2e5, -3e5, 0};
    double log_f, omega[4];
    TRY(bingham_log_normalization_constant(4, zbig, &log_f, omega));
    printf("  log F(-1e5, -2e5, -3e5, 0) = %.15g, omega = E[x_i^2] = (%.3g, %.3g, %.3g, %.15g)\n",
           log_f, omega[0], omega[1], omega[2], omega[3]);

    /* 2. A quaternion distribution: M's columns are principal directions, the last one (z = 0
     *    after sorting) is the mode. Quaternions are scalar first (w, x, y, z). */
    const double c = cos(0.4), s = sin(0.4);
    const double m[16] = {c, -s, 0, 0, /* row-major: a rotation in the (w, x) plane */
                          s, c,  0, 0,
                          0, 0,  1, 0,
                          0, 0,  0, 1};
    double sm[16], mode[4];
    TRY(bingham_second_moment(4, m, z, sm));
    if (verbose && *verbose && strcmp(verbose, "0") != 0) print_matrix("  second moment S = E[x x^T]", sm, 4);
    printf("  second moment S = E[x x^T]: diagonal (%.5f, %.5f, %.5f, %.5f), S_wx = %.5f\n", sm[0], sm[5],
           sm[10], sm[15], sm[1]);
    TRY(bingham_mode(4, m, z, mode));
    print_vector("  mode", mode, 4);

    /* 3. Maximum likelihood (moment matching) recovers the distribution from S. */
    double m_fit[16], z_fit[4];
    TRY(bingham_mle(4, sm, m_fit, z_fit));
    print_vector(", MLE from S: z (sorted, last = 0)", z_fit, 4);
    printf("\n");

    /* ... and from samples. */
    enum { N = 5000 };
    static double x[N * 4];
    TRY(bingham_sample(4, m, z, 2024, N, x));
    TRY(bingham_mle_samples(4, N, x, NULL, m_fit, z_fit));
    print_vector("  MLE from 5000 samples: z", z_fit, 4);

    double p[2];
    TRY(bingham_pdf(4, m, z, 2, x, p));
    printf(", pdf at the first two: %.6g, %.6g\n", p[0], p[1]);

    /* 4. Bayes: multiply prior and likelihood. A measurement with the prior's mode (0, 0, 1, 0)
     *    as its mode: the concentrations add up and the mode stays. */
    const double m_meas[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 1, 0, 0, 1, 0};
    const double z_meas[4] = {-100, -100, -100, 0};
    double m_post[16], z_post[4] = {0};
    TRY(bingham_multiply(4, m, z, m_meas, z_meas, m_post, z_post));
    print_vector("  Bayes product: posterior z", z_post, 4);
    TRY(bingham_mode(4, m_post, z_post, mode));
    print_vector(", mode", mode, 4);
    printf("\n");

    /* 5. Composition (prediction): x (+) w for noise w concentrated at the identity quaternion
     *    (1, 0, 0, 0): M_w = anti-diagonal so that its last column is (1, 0, 0, 0). */
    const double m_w[16] = {0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 0};
    const double z_w[4] = {-200, -200, -2, 0};
    double m_pred[16], z_pred[4];
    TRY(bingham_compose(4, m_post, z_post, m_w, z_w, m_pred, z_pred));
    print_vector("  composition with noise: predicted z (less concentrated)", z_pred, 4);
    printf("\n");

    /* 6. Errors: a status, a static name, and a thread-local message; outputs untouched. */
    const double bad_z[4] = {-1, INFINITY, 0, 0};
    bingham_status st = bingham_normalization_constant(4, bad_z, &f, NULL);
    char msg[256];
    size_t len;
    bingham_last_error_message(msg, sizeof msg, &len);
    printf("  refused input (z[1] = +Inf): status %d (%s): %s\n", (int)st, bingham_status_str(st), msg);
    return 0;
}
