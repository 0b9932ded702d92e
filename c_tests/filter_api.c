/* The C API of the recursive Bingham filter (bingham_filter_*), function by function, for
 * d = 2 and d = 4:
 *
 * - the success path of every function;
 * - bingham_filter_new with d = 0, 1, 3, 5, 64, 65, SIZE_MAX -> BINGHAM_ERR_INVALID_DIMENSION,
 *   with the arrays aimed at an inaccessible (PROT_NONE) page, so a read before the check would
 *   crash;
 * - every pointer argument set to NULL -> BINGHAM_ERR_NULL_ARGUMENT;
 * - NaN and +-Inf in every input array, non-orthogonal matrices and non-unit vectors just
 *   outside the 1e-6 tolerances -> BINGHAM_ERR_INVALID_ARGUMENT (just inside: accepted);
 * - after every failure: the filter state bit-for-bit unchanged, output buffers untouched
 *   (sentinel fill), a last error message naming the function;
 * - inputs placed flush against an inaccessible page: nothing is read beyond d (d*d) entries;
 * - clones evolve exactly like the original; handles on different threads are independent;
 *   const functions may run concurrently on one handle.
 * - bingham_filter_surprise (d = 4 and d = 2, a noise whose mode is neither the identity nor in
 *   the last column): 2 (ll(y_hat) - ll(y)) from bingham_filter_log_likelihood, y_hat the state's
 *   mode times the noise's mode (the group product written out here), to 1e-9 relative; 0 at
 *   y_hat; growing with the distance from y_hat; the same for -y; errors leave the output and
 *   state alone;
 * - bingham_filter_update_gated: a near measurement under the 0.1 % chi-square level (16.27,
 *   d = 2: 10.83) applied, the state bit for bit bingham_filter_update's on a clone; a far one
 *   gated out with BINGHAM_OK and the state bit for bit unchanged; accepted iff
 *   surprise <= max_surprise (at the boundary and one ulp below), INFINITY no gate; NaN or
 *   negative max_surprise -> INVALID_ARGUMENT, NULL outputs -> NULL_ARGUMENT, outputs untouched.
 */
#define _DEFAULT_SOURCE 1
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>

#include "check.h"
#include "api_util.h"

static const double PI = 3.14159265358979323846;

typedef struct {
    size_t d;
    double m0[16], z0[4], mw[16], zw[4], mv[16], zv[4], x0[4];
} scenario;

static scenario scenario_2d(void) {
    scenario s = {2, {1, 0, 0, 1}, {-1, 0}, {0, 1, 1, 0}, {-200, 0}, {0, 1, 1, 0}, {-2, 0}, {1, 0}};
    return s;
}

static scenario scenario_4d(void) {
    scenario s = {4,
                  {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1},
                  {-1, -1, -1, 0},
                  {0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 0},
                  {-200, -200, -2, 0},
                  {0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 0},
                  {-500, -500, -500, 0},
                  {0, 1, 0, 0}};
    return s;
}

static int last_error_names(const char *fn) {
    char msg[1024];
    bingham_last_error_message(msg, sizeof msg, NULL);
    return strstr(msg, fn) != NULL;
}

/* Expects `call` to fail with `expected`, the state of `f` unchanged, the message naming `fn`. */
#define CHECK_FAILS(f, call, expected, fn)                                                       \
    do {                                                                                         \
        snapshot check_before_ = snap(f);                                                        \
        CHECK_STATUS(call, expected);                                                            \
        CHECK(same(check_before_, snap(f)));                                                     \
        CHECK(last_error_names(fn));                                                             \
    } while (0)

static void unit_measurement(size_t d, double angle, double *out) {
    size_t i;
    for (i = 0; i < d; ++i) out[i] = 0;
    out[0] = cos(angle);
    out[1] = sin(angle);
    if (d == 4) {
        out[1] *= 0.6;
        out[2] = 0.8 * sin(angle);
    }
}

/* ---- bingham_filter_new ------------------------------------------------------------------- */

static void test_new(const scenario *s) {
    size_t d = s->d, i, bad_d[] = {0, 1, 3, 5, 64, 65, (size_t)-1};
    bingham_filter *f = NULL, *sentinel_handle = (bingham_filter *)&bad_d, *out;
    double m[16], z[4];

    CHECK_OK(bingham_filter_new(d, flush(s->m0, d * d), s->z0, &f));
    CHECK(f != NULL);
    CHECK_OK(bingham_filter_get_state(f, m, z));
    CHECK(z[d - 1] == 0.0);
    bingham_filter_free(f);
    CHECK_OK(bingham_filter_new(d, s->m0, flush(s->z0, d), &f));
    bingham_filter_free(f);

    for (i = 0; i < sizeof bad_d / sizeof bad_d[0]; ++i) {
        out = sentinel_handle;
        CHECK_STATUS(bingham_filter_new(bad_d[i], no_access(), no_access(), &out),
                     BINGHAM_ERR_INVALID_DIMENSION);
        CHECK(out == sentinel_handle);
        CHECK(last_error_names("bingham_filter_new"));
    }
    out = sentinel_handle;
    CHECK_STATUS(bingham_filter_new(d, NULL, s->z0, &out), BINGHAM_ERR_NULL_ARGUMENT);
    CHECK_STATUS(bingham_filter_new(d, s->m0, NULL, &out), BINGHAM_ERR_NULL_ARGUMENT);
    CHECK_STATUS(bingham_filter_new(d, s->m0, s->z0, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    CHECK(out == sentinel_handle);
    for (i = 0; i < d * d + d; ++i) {
        double bad[3] = {NAN, INFINITY, -INFINITY};
        int k;
        for (k = 0; k < 3; ++k) {
            memcpy(m, s->m0, sizeof m);
            memcpy(z, s->z0, sizeof z);
            if (i < d * d)
                m[i] = bad[k];
            else
                z[i - d * d] = bad[k];
            CHECK_STATUS(bingham_filter_new(d, m, z, &out), BINGHAM_ERR_INVALID_ARGUMENT);
            CHECK(out == sentinel_handle);
        }
    }
    /* orthogonality tolerance 1e-6 on max |M^T M - I| */
    memcpy(m, s->m0, sizeof m);
    m[0] += 2e-6;
    CHECK_STATUS(bingham_filter_new(d, m, s->z0, &out), BINGHAM_ERR_INVALID_ARGUMENT);
    CHECK(out == sentinel_handle);
    CHECK(last_error_names("orthogonal"));
    m[0] = s->m0[0] + 2e-7;
    CHECK_OK(bingham_filter_new(d, m, s->z0, &f));
    bingham_filter_free(f);
    bingham_filter_free(NULL);
}

/* ---- everything on a live handle --------------------------------------------------------- */

static void test_handle(const scenario *s) {
    size_t d = s->d, dd = d * d, i, dim = 0;
    bingham_filter *f = NULL, *g = NULL, *sentinel_handle = (bingham_filter *)&dim, *out;
    double y[4], m[16], z[4], mode[4], ll = 0, bad[16];
    snapshot before;

    CHECK_OK(bingham_filter_new(d, s->m0, s->z0, &f));

    /* dim */
    CHECK_OK(bingham_filter_dim(f, &dim));
    CHECK(dim == d);
    CHECK_STATUS(bingham_filter_dim(NULL, &dim), BINGHAM_ERR_NULL_ARGUMENT);
    CHECK_STATUS(bingham_filter_dim(f, NULL), BINGHAM_ERR_NULL_ARGUMENT);

    /* predict: success, reading exactly d*d and d entries */
    CHECK_OK(bingham_filter_predict(f, flush(s->mw, dd), s->zw));
    CHECK_OK(bingham_filter_predict(f, s->mw, flush(s->zw, d)));
    CHECK_FAILS(f, bingham_filter_predict(NULL, s->mw, s->zw), BINGHAM_ERR_NULL_ARGUMENT,
                "bingham_filter_predict");
    CHECK_FAILS(f, bingham_filter_predict(f, NULL, s->zw), BINGHAM_ERR_NULL_ARGUMENT,
                "bingham_filter_predict");
    CHECK_FAILS(f, bingham_filter_predict(f, s->mw, NULL), BINGHAM_ERR_NULL_ARGUMENT,
                "bingham_filter_predict");
    for (i = 0; i < dd + d; ++i) {
        double nz[4];
        memcpy(bad, s->mw, sizeof bad);
        memcpy(nz, s->zw, sizeof nz);
        if (i < dd)
            bad[i] = (i % 2) ? INFINITY : NAN;
        else
            nz[i - dd] = (i % 2) ? -INFINITY : NAN;
        CHECK_FAILS(f, bingham_filter_predict(f, bad, nz), BINGHAM_ERR_INVALID_ARGUMENT,
                    "bingham_filter_predict");
    }
    memcpy(bad, s->mw, sizeof bad);
    bad[1] += 2e-6; /* not orthogonal */
    CHECK_FAILS(f, bingham_filter_predict(f, bad, s->zw), BINGHAM_ERR_INVALID_ARGUMENT,
                "bingham_filter_predict");
    bad[1] = s->mw[1] + 2e-7; /* within the tolerance */
    CHECK_OK(bingham_filter_predict(f, bad, s->zw));

    /* predict_rotation */
    unit_measurement(d, 0.3, y);
    CHECK_OK(bingham_filter_predict_rotation(f, flush(y, d), s->mw, s->zw));
    CHECK_FAILS(f, bingham_filter_predict_rotation(NULL, y, s->mw, s->zw),
                BINGHAM_ERR_NULL_ARGUMENT, "bingham_filter_predict_rotation");
    CHECK_FAILS(f, bingham_filter_predict_rotation(f, NULL, s->mw, s->zw),
                BINGHAM_ERR_NULL_ARGUMENT, "bingham_filter_predict_rotation");
    CHECK_FAILS(f, bingham_filter_predict_rotation(f, y, NULL, s->zw), BINGHAM_ERR_NULL_ARGUMENT,
                "bingham_filter_predict_rotation");
    CHECK_FAILS(f, bingham_filter_predict_rotation(f, y, s->mw, NULL), BINGHAM_ERR_NULL_ARGUMENT,
                "bingham_filter_predict_rotation");
    for (i = 0; i < d; ++i) {
        double u[4];
        memcpy(u, y, sizeof u);
        u[i] = NAN;
        CHECK_FAILS(f, bingham_filter_predict_rotation(f, u, s->mw, s->zw),
                    BINGHAM_ERR_INVALID_ARGUMENT, "bingham_filter_predict_rotation");
    }
    {
        double u[4], zero[4] = {0, 0, 0, 0};
        for (i = 0; i < d; ++i) u[i] = y[i] * (1 + 2e-3); /* beyond BINGHAM_UNIT_TOL */
        CHECK_FAILS(f, bingham_filter_predict_rotation(f, u, s->mw, s->zw),
                    BINGHAM_ERR_INVALID_ARGUMENT, "bingham_filter_predict_rotation");
        CHECK(last_error_names("unit"));
        CHECK_FAILS(f, bingham_filter_predict_rotation(f, zero, s->mw, s->zw),
                    BINGHAM_ERR_INVALID_ARGUMENT, "bingham_filter_predict_rotation");
        for (i = 0; i < d; ++i) u[i] = y[i] * (1 + 5e-7);
        CHECK_OK(bingham_filter_predict_rotation(f, u, s->mw, s->zw));
    }
    memcpy(bad, s->mw, sizeof bad);
    bad[1] += 2e-6;
    CHECK_FAILS(f, bingham_filter_predict_rotation(f, y, bad, s->zw),
                BINGHAM_ERR_INVALID_ARGUMENT, "bingham_filter_predict_rotation");

    /* update */
    unit_measurement(d, 0.5, y);
    /* one flush() buffer at a time: they share the page end */
    CHECK_OK(bingham_filter_update(f, flush(y, d), s->mv, s->zv));
    CHECK_OK(bingham_filter_update(f, y, flush(s->mv, dd), s->zv));
    CHECK_OK(bingham_filter_update(f, y, s->mv, flush(s->zv, d)));
    CHECK_FAILS(f, bingham_filter_update(NULL, y, s->mv, s->zv), BINGHAM_ERR_NULL_ARGUMENT,
                "bingham_filter_update");
    CHECK_FAILS(f, bingham_filter_update(f, NULL, s->mv, s->zv), BINGHAM_ERR_NULL_ARGUMENT,
                "bingham_filter_update");
    CHECK_FAILS(f, bingham_filter_update(f, y, NULL, s->zv), BINGHAM_ERR_NULL_ARGUMENT,
                "bingham_filter_update");
    CHECK_FAILS(f, bingham_filter_update(f, y, s->mv, NULL), BINGHAM_ERR_NULL_ARGUMENT,
                "bingham_filter_update");
    for (i = 0; i < d + dd + d; ++i) {
        double yy[4], mm[16], zz[4];
        memcpy(yy, y, sizeof yy);
        memcpy(mm, s->mv, sizeof mm);
        memcpy(zz, s->zv, sizeof zz);
        if (i < d)
            yy[i] = NAN;
        else if (i < d + dd)
            mm[i - d] = INFINITY;
        else
            zz[i - d - dd] = -INFINITY;
        CHECK_FAILS(f, bingham_filter_update(f, yy, mm, zz), BINGHAM_ERR_INVALID_ARGUMENT,
                    "bingham_filter_update");
    }
    {
        double yy[4];
        for (i = 0; i < d; ++i) yy[i] = y[i] * (1 - 2e-3);
        CHECK_FAILS(f, bingham_filter_update(f, yy, s->mv, s->zv), BINGHAM_ERR_INVALID_ARGUMENT,
                    "bingham_filter_update");
        CHECK(last_error_names("measurement"));
        for (i = 0; i < d; ++i) yy[i] = -y[i] * (1 - 5e-7); /* the sign does not matter */
        CHECK_OK(bingham_filter_update(f, yy, s->mv, s->zv));
    }
    memcpy(bad, s->mv, sizeof bad);
    bad[dd - 1] -= 2e-6;
    CHECK_FAILS(f, bingham_filter_update(f, y, bad, s->zv), BINGHAM_ERR_INVALID_ARGUMENT,
                "bingham_filter_update");

    /* log_likelihood: const, output written only on success */
    before = snap(f);
    CHECK_OK(bingham_filter_log_likelihood(f, flush(y, d), s->mv, s->zv, &ll));
    CHECK(isfinite(ll));
    CHECK(same(before, snap(f)));
    {
        double yy[4], ll2 = 0;
        for (i = 0; i < d; ++i) yy[i] = -y[i];
        CHECK_OK(bingham_filter_log_likelihood(f, yy, s->mv, s->zv, &ll2));
        CHECK_CLOSE(ll2, ll, 1e-12);
        ll2 = 12345.0;
        CHECK_STATUS(bingham_filter_log_likelihood(NULL, y, s->mv, s->zv, &ll2),
                     BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_STATUS(bingham_filter_log_likelihood(f, NULL, s->mv, s->zv, &ll2),
                     BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_STATUS(bingham_filter_log_likelihood(f, y, NULL, s->zv, &ll2),
                     BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_STATUS(bingham_filter_log_likelihood(f, y, s->mv, NULL, &ll2),
                     BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_STATUS(bingham_filter_log_likelihood(f, y, s->mv, s->zv, NULL),
                     BINGHAM_ERR_NULL_ARGUMENT);
        for (i = 0; i < d; ++i) yy[i] = y[i] * 1.01;
        CHECK_STATUS(bingham_filter_log_likelihood(f, yy, s->mv, s->zv, &ll2),
                     BINGHAM_ERR_INVALID_ARGUMENT);
        yy[0] = NAN;
        CHECK_STATUS(bingham_filter_log_likelihood(f, yy, s->mv, s->zv, &ll2),
                     BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK_STATUS(bingham_filter_log_likelihood(f, y, bad, s->zv, &ll2),
                     BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK(last_error_names("bingham_filter_log_likelihood"));
        CHECK(ll2 == 12345.0);
        CHECK(same(before, snap(f)));
    }

    /* mode and get_state: outputs only on success */
    CHECK_OK(bingham_filter_mode(f, mode));
    CHECK_OK(bingham_filter_get_state(f, m, z));
    for (i = 0; i < d; ++i) CHECK(mode[i] == m[i * d + d - 1]);
    for (i = 0; i + 1 < d; ++i) CHECK(z[i] <= z[i + 1]);
    CHECK(z[d - 1] == 0.0);
    {
        double sm[16], sz[4], smode[4];
        for (i = 0; i < 16; ++i) sm[i] = 777.0;
        for (i = 0; i < 4; ++i) sz[i] = smode[i] = 777.0;
        CHECK_STATUS(bingham_filter_mode(NULL, smode), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_STATUS(bingham_filter_mode(f, NULL), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_STATUS(bingham_filter_get_state(NULL, sm, sz), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_STATUS(bingham_filter_get_state(f, NULL, sz), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_STATUS(bingham_filter_get_state(f, sm, NULL), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK(last_error_names("bingham_filter_get_state"));
        for (i = 0; i < 16; ++i) CHECK(sm[i] == 777.0);
        for (i = 0; i < 4; ++i) CHECK(sz[i] == 777.0 && smode[i] == 777.0);
    }

    /* set_state */
    CHECK_FAILS(f, bingham_filter_set_state(NULL, s->m0, s->z0), BINGHAM_ERR_NULL_ARGUMENT,
                "bingham_filter_set_state");
    CHECK_FAILS(f, bingham_filter_set_state(f, NULL, s->z0), BINGHAM_ERR_NULL_ARGUMENT,
                "bingham_filter_set_state");
    CHECK_FAILS(f, bingham_filter_set_state(f, s->m0, NULL), BINGHAM_ERR_NULL_ARGUMENT,
                "bingham_filter_set_state");
    memcpy(bad, s->m0, sizeof bad);
    bad[d] = NAN;
    CHECK_FAILS(f, bingham_filter_set_state(f, bad, s->z0), BINGHAM_ERR_INVALID_ARGUMENT,
                "bingham_filter_set_state");
    memcpy(bad, s->m0, sizeof bad);
    bad[d] = 1e-5;
    CHECK_FAILS(f, bingham_filter_set_state(f, bad, s->z0), BINGHAM_ERR_INVALID_ARGUMENT,
                "bingham_filter_set_state");
    {
        double zz[4];
        memcpy(zz, s->z0, sizeof zz);
        zz[0] = INFINITY;
        CHECK_FAILS(f, bingham_filter_set_state(f, s->m0, zz), BINGHAM_ERR_INVALID_ARGUMENT,
                    "bingham_filter_set_state");
        /* success: any order and shift in, sorted and shifted out */
        for (i = 0; i < d; ++i) zz[i] = 5.0 - (double)i;
        CHECK_OK(bingham_filter_set_state(f, flush(s->m0, dd), zz));
        CHECK_OK(bingham_filter_get_state(f, m, z));
        for (i = 0; i < d; ++i) CHECK(z[i] == -(double)(d - 1 - i));
        /* the mode is the column with the largest z: the first one */
        CHECK_OK(bingham_filter_mode(f, mode));
        CHECK(fabs(fabs(mode[0]) - 1) < 1e-15);
    }

    /* clone: an independent copy that evolves exactly like the original */
    out = sentinel_handle;
    CHECK_STATUS(bingham_filter_clone(NULL, &out), BINGHAM_ERR_NULL_ARGUMENT);
    CHECK_STATUS(bingham_filter_clone(f, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    CHECK(out == sentinel_handle);
    CHECK_OK(bingham_filter_clone(f, &g));
    CHECK(same(snap(f), snap(g)));
    for (i = 0; i < 20; ++i) {
        unit_measurement(d, 0.1 * (double)i, y);
        CHECK_OK(bingham_filter_predict(f, s->mw, s->zw));
        CHECK_OK(bingham_filter_predict(g, s->mw, s->zw));
        CHECK_OK(bingham_filter_update(f, y, s->mv, s->zv));
        CHECK_OK(bingham_filter_update(g, y, s->mv, s->zv));
    }
    CHECK(same(snap(f), snap(g)));
    CHECK_OK(bingham_filter_update(g, y, s->mv, s->zv));
    CHECK(!same(snap(f), snap(g)));
    bingham_filter_free(g);
    bingham_filter_free(f);
}

/* A very sharp state: predict never fails, update stays finite (documented cap). */
static void test_sharp(const scenario *s) {
    size_t d = s->d, i, k;
    bingham_filter *f = NULL;
    double z[4], zs[4], m[16], y[4];
    for (i = 0; i < d; ++i) zs[i] = (i + 1 == d) ? 0 : -1e13;
    CHECK_OK(bingham_filter_new(d, s->m0, zs, &f));
    CHECK_OK(bingham_filter_predict(f, s->mw, zs));
    CHECK_OK(bingham_filter_get_state(f, m, z));
    CHECK(z[0] >= -1.01 * BINGHAM_FILTER_MAX_CONCENTRATION && isfinite(z[0]));
    CHECK_OK(bingham_filter_mode(f, y));
    for (k = 0; k < 50; ++k) CHECK_OK(bingham_filter_update(f, y, s->mv, zs));
    CHECK_OK(bingham_filter_get_state(f, m, z));
    for (i = 0; i < d; ++i) CHECK(isfinite(z[i]));
    CHECK(z[0] < -1e14);
    CHECK_OK(bingham_filter_predict(f, s->mw, s->zw));
    bingham_filter_free(f);
}

/* ---- surprise and the gated update ------------------------------------------------------------- */

/* The group product: Hamilton's for quaternions (w, x, y, z), complex for d = 2. */
static void group_mul(size_t d, const double *a, const double *b, double *out) {
    double r[4];
    if (d == 2) {
        r[0] = a[0] * b[0] - a[1] * b[1];
        r[1] = a[0] * b[1] + a[1] * b[0];
    } else {
        r[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
        r[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
        r[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
        r[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
    }
    memcpy(out, r, d * sizeof(double));
}

/* An orthogonal d x d matrix (row-major): the identity turned by Givens rotations in the planes
 * (i, i+1) by the angles phase + 0.4 i. */
static void givens_orthogonal(size_t d, double phase, double *m) {
    size_t i, r;
    memset(m, 0, d * d * sizeof *m);
    for (i = 0; i < d; ++i) m[i * d + i] = 1.0;
    for (i = 0; i + 1 < d; ++i) {
        double c = cos(phase + 0.4 * (double)i), s = sin(phase + 0.4 * (double)i);
        for (r = 0; r < d; ++r) {
            double x = m[r * d + i], y = m[r * d + i + 1];
            m[r * d + i] = c * x - s * y;
            m[r * d + i + 1] = s * x + c * y;
        }
    }
}

/* 2 (ll(y_hat) - ll(y)) clamped at 0, from bingham_filter_log_likelihood. */
static double surprise_from_ll(const bingham_filter *f, const double *y_hat, const double *y, const double *mv,
                               const double *zv) {
    double l_hat = 0, l_y = 0, s;
    CHECK_OK(bingham_filter_log_likelihood(f, y_hat, mv, zv, &l_hat));
    CHECK_OK(bingham_filter_log_likelihood(f, y, mv, zv, &l_y));
    s = 2.0 * (l_hat - l_y);
    return s > 0.0 ? s : 0.0;
}

static void test_surprise(size_t d) {
    const char *fs = "bingham_filter_surprise", *fg = "bingham_filter_update_gated";
    const double max_s = d == 4 ? 16.27 : 10.83; /* chi-square(d - 1), 0.1 % */
    size_t i, top;
    double m0[16], z0[4], mv[16], zv[4], x_hat[4], v_hat[4], y_hat[4], y[4], dq[4], s = 0, s2 = 0, expect;
    bingham_filter *f = NULL, *g = NULL;
    snapshot before;

    /* a state with a non-trivial mode; a noise whose mode is not the identity, its largest
     * concentration (0) not in the last place */
    givens_orthogonal(d, 0.3, m0);
    givens_orthogonal(d, -0.7, mv);
    if (d == 4) {
        const double z0v[4] = {-4000, -2500, -1200, 0}, zvv[4] = {-3000, 0, -6000, -4500};
        memcpy(z0, z0v, sizeof z0);
        memcpy(zv, zvv, sizeof zv);
    } else {
        const double z0v[2] = {-3000, 0}, zvv[2] = {0, -5000};
        memcpy(z0, z0v, 2 * sizeof(double));
        memcpy(zv, zvv, 2 * sizeof(double));
    }
    CHECK_OK(bingham_filter_new(d, m0, z0, &f));
    if (!f) return;
    /* y_hat = (state mode) (+) (noise mode): the columns of the largest concentrations */
    CHECK_OK(bingham_filter_mode(f, x_hat));
    for (top = 0, i = 1; i < d; ++i)
        if (zv[i] > zv[top]) top = i;
    for (i = 0; i < d; ++i) v_hat[i] = mv[i * d + top];
    group_mul(d, x_hat, v_hat, y_hat);
    normalize(y_hat, d);

    /* at y_hat itself: 0 */
    CHECK_OK(bingham_filter_surprise(f, y_hat, mv, zv, &s));
    CHECK(s >= 0.0 && s <= 1e-9);
    /* measurements around y_hat, near and far: the log-likelihood difference */
    for (i = 0; i < 6; ++i) {
        double angle = 0.01 * (double)(i * i + 1); /* 0.01 .. 0.26 rad */
        dq[0] = cos(angle / 2);
        dq[1] = sin(angle / 2) * (d == 4 ? 0.48 : 1.0);
        if (d == 4) dq[2] = sin(angle / 2) * 0.6, dq[3] = sin(angle / 2) * -0.64;
        group_mul(d, y_hat, dq, y);
        CHECK_OK(bingham_filter_surprise(f, y, mv, zv, &s));
        expect = surprise_from_ll(f, y_hat, y, mv, zv);
        CHECK(s >= 0.0);
        CHECK(fabs(s - expect) <= 1e-9 * fabs(expect) + 1e-12);
        if (i > 0) CHECK(s > s2); /* further away: more surprising */
        s2 = s;
        /* the sign of the measurement does not matter */
        {
            double ny[4], sn = 0;
            size_t k;
            for (k = 0; k < d; ++k) ny[k] = -y[k];
            CHECK_OK(bingham_filter_surprise(f, ny, mv, zv, &sn));
            CHECK_CLOSE(sn, s, 1e-9);
        }
    }
    CHECK(s2 > max_s); /* 0.26 rad: well beyond the 0.1 % level */

    /* surprise: errors, output untouched, state unchanged */
    {
        double out = 12345.0, yy[4];
        CHECK_FAILS(f, bingham_filter_surprise(NULL, y, mv, zv, &out), BINGHAM_ERR_NULL_ARGUMENT, fs);
        CHECK_FAILS(f, bingham_filter_surprise(f, NULL, mv, zv, &out), BINGHAM_ERR_NULL_ARGUMENT, fs);
        CHECK_FAILS(f, bingham_filter_surprise(f, y, NULL, zv, &out), BINGHAM_ERR_NULL_ARGUMENT, fs);
        CHECK_FAILS(f, bingham_filter_surprise(f, y, mv, NULL, &out), BINGHAM_ERR_NULL_ARGUMENT, fs);
        CHECK_FAILS(f, bingham_filter_surprise(f, y, mv, zv, NULL), BINGHAM_ERR_NULL_ARGUMENT, fs);
        memcpy(yy, y, sizeof yy);
        yy[1] = NAN;
        CHECK_FAILS(f, bingham_filter_surprise(f, yy, mv, zv, &out), BINGHAM_ERR_INVALID_ARGUMENT, fs);
        for (i = 0; i < d; ++i) yy[i] = y[i] * 1.01;
        CHECK_FAILS(f, bingham_filter_surprise(f, yy, mv, zv, &out), BINGHAM_ERR_INVALID_ARGUMENT, fs);
        CHECK(out == 12345.0);
        /* reads exactly d, d*d, d entries */
        CHECK_OK(bingham_filter_surprise(f, flush(y, d), mv, zv, &out));
        CHECK_OK(bingham_filter_surprise(f, y, flush(mv, d * d), zv, &out));
        CHECK_OK(bingham_filter_surprise(f, y, mv, flush(zv, d), &out));
    }

    /* the gated update: a near measurement (0.01 rad from y_hat) is applied, bit for bit
     * bingham_filter_update on a clone */
    dq[0] = cos(0.005);
    dq[1] = sin(0.005);
    if (d == 4) dq[1] = 0.0, dq[2] = sin(0.005), dq[3] = 0.0;
    group_mul(d, y_hat, dq, y);
    {
        double sg = -1.0, s_ref = -2.0;
        int32_t acc = 7;
        CHECK_OK(bingham_filter_surprise(f, y, mv, zv, &s_ref));
        CHECK(s_ref < max_s);
        CHECK_OK(bingham_filter_clone(f, &g));
        if (!g) return;
        CHECK_OK(bingham_filter_update_gated(f, y, mv, zv, max_s, &sg, &acc));
        CHECK(acc == 1 && sg == s_ref);
        CHECK_OK(bingham_filter_update(g, y, mv, zv));
        CHECK(same(snap(f), snap(g)));
        bingham_filter_free(g);
        g = NULL;
    }
    /* a far measurement (0.5 rad): gated out, BINGHAM_OK, the state bit for bit as before */
    dq[0] = cos(0.25);
    dq[1] = sin(0.25);
    if (d == 4) dq[1] = sin(0.25) * 0.6, dq[2] = 0.0, dq[3] = sin(0.25) * 0.8;
    CHECK_OK(bingham_filter_mode(f, x_hat));
    group_mul(d, x_hat, v_hat, y_hat);
    group_mul(d, y_hat, dq, y);
    {
        double sg = -1.0, s_ref = -2.0;
        int32_t acc = 7;
        CHECK_OK(bingham_filter_surprise(f, y, mv, zv, &s_ref));
        CHECK(s_ref > max_s);
        CHECK_CLOSE(s_ref, surprise_from_ll(f, y_hat, y, mv, zv), 1e-9);
        before = snap(f);
        CHECK_OK(bingham_filter_update_gated(f, y, mv, zv, max_s, &sg, &acc));
        CHECK(acc == 0 && sg == s_ref);
        CHECK(same(before, snap(f)));
        /* the boundary: accepted iff surprise <= max_surprise */
        CHECK_OK(bingham_filter_clone(f, &g));
        if (!g) return;
        acc = 7;
        CHECK_OK(bingham_filter_update_gated(f, y, mv, zv, nextafter(s_ref, 0.0), &sg, &acc));
        CHECK(acc == 0 && same(before, snap(f)));
        CHECK_OK(bingham_filter_update_gated(f, y, mv, zv, s_ref, &sg, &acc));
        CHECK(acc == 1 && sg == s_ref);
        CHECK_OK(bingham_filter_update(g, y, mv, zv));
        CHECK(same(snap(f), snap(g)));
        /* INFINITY: no gate */
        CHECK_OK(bingham_filter_set_state(f, before.m, before.z));
        CHECK_OK(bingham_filter_set_state(g, before.m, before.z));
        CHECK(same(snap(f), before));
        acc = 7;
        CHECK_OK(bingham_filter_update_gated(f, y, mv, zv, INFINITY, &sg, &acc));
        CHECK(acc == 1 && sg == s_ref);
        CHECK_OK(bingham_filter_update(g, y, mv, zv));
        CHECK(same(snap(f), snap(g)));
        bingham_filter_free(g);
        g = NULL;
    }

    /* errors: NaN / negative max_surprise, NULLs, a bad measurement: outputs untouched (sentinel
     * values), the state unchanged, the message naming the function */
    {
        const double bad_max[4] = {NAN, -1.0, -INFINITY, -1e-300};
        double sg = 12345.0, yy[4];
        int32_t acc = 0x5A5A5A5A;
        for (i = 0; i < 4; ++i) {
            CHECK_FAILS(f, bingham_filter_update_gated(f, y, mv, zv, bad_max[i], &sg, &acc),
                        BINGHAM_ERR_INVALID_ARGUMENT, fg);
            CHECK(last_error_names("max_surprise"));
        }
        CHECK_FAILS(f, bingham_filter_update_gated(f, y, mv, zv, max_s, NULL, &acc), BINGHAM_ERR_NULL_ARGUMENT, fg);
        CHECK_FAILS(f, bingham_filter_update_gated(f, y, mv, zv, max_s, &sg, NULL), BINGHAM_ERR_NULL_ARGUMENT, fg);
        CHECK_FAILS(f, bingham_filter_update_gated(NULL, y, mv, zv, max_s, &sg, &acc), BINGHAM_ERR_NULL_ARGUMENT, fg);
        CHECK_FAILS(f, bingham_filter_update_gated(f, NULL, mv, zv, max_s, &sg, &acc), BINGHAM_ERR_NULL_ARGUMENT, fg);
        CHECK_FAILS(f, bingham_filter_update_gated(f, y, NULL, zv, max_s, &sg, &acc), BINGHAM_ERR_NULL_ARGUMENT, fg);
        CHECK_FAILS(f, bingham_filter_update_gated(f, y, mv, NULL, max_s, &sg, &acc), BINGHAM_ERR_NULL_ARGUMENT, fg);
        memcpy(yy, y, sizeof yy);
        yy[0] = INFINITY;
        CHECK_FAILS(f, bingham_filter_update_gated(f, yy, mv, zv, INFINITY, &sg, &acc), BINGHAM_ERR_INVALID_ARGUMENT,
                    fg);
        CHECK(sg == 12345.0 && acc == 0x5A5A5A5A);
    }
    bingham_filter_free(f);
}

/* ---- threads ------------------------------------------------------------------------------ */

typedef struct {
    scenario s;
    const bingham_filter *shared;
    snapshot result;
    double ll;
    int ok;
} job;

static void run_steps(const scenario *s, bingham_filter *f, int *ok) {
    int k;
    double y[4];
    for (k = 0; k < 200; ++k) {
        unit_measurement(s->d, 0.05 * k + 0.3 * sin(1.7 * k), y);
        *ok &= bingham_filter_predict(f, s->mw, s->zw) == BINGHAM_OK;
        *ok &= bingham_filter_update(f, y, s->mv, s->zv) == BINGHAM_OK;
    }
}

static void *thread_main(void *arg) {
    job *j = (job *)arg;
    bingham_filter *f = NULL;
    int k;
    double y[4];
    j->ok = bingham_filter_new(j->s.d, j->s.m0, j->s.z0, &f) == BINGHAM_OK;
    if (!j->ok) return NULL;
    run_steps(&j->s, f, &j->ok);
    j->result = snap(f);
    bingham_filter_free(f);
    /* concurrent const use of one shared handle */
    unit_measurement(j->s.d, 0.7, y);
    for (k = 0; k < 100; ++k)
        j->ok &= bingham_filter_log_likelihood(j->shared, y, j->s.mv, j->s.zv, &j->ll) ==
                 BINGHAM_OK;
    return NULL;
}

static void test_threads(const scenario *s) {
    enum { T = 4 };
    pthread_t th[T];
    job jobs[T];
    bingham_filter *ref = NULL, *shared = NULL;
    double y[4], ll;
    int ok = 1, t;
    snapshot expect;
    CHECK_OK(bingham_filter_new(s->d, s->m0, s->z0, &ref));
    run_steps(s, ref, &ok);
    CHECK(ok);
    expect = snap(ref);
    CHECK_OK(bingham_filter_new(s->d, s->m0, s->z0, &shared));
    unit_measurement(s->d, 0.7, y);
    CHECK_OK(bingham_filter_log_likelihood(shared, y, s->mv, s->zv, &ll));
    for (t = 0; t < T; ++t) {
        jobs[t].s = *s;
        jobs[t].shared = shared;
        CHECK(pthread_create(&th[t], NULL, thread_main, &jobs[t]) == 0);
    }
    for (t = 0; t < T; ++t) {
        CHECK(pthread_join(th[t], NULL) == 0);
        CHECK(jobs[t].ok);
        CHECK(same(jobs[t].result, expect));
        CHECK(jobs[t].ll == ll);
    }
    bingham_filter_free(shared);
    bingham_filter_free(ref);
}

int main(void) {
    scenario sc[2];
    int i;
    if (guard_pages_init()) return 1;
    sc[0] = scenario_2d();
    sc[1] = scenario_4d();
    for (i = 0; i < 2; ++i) {
        test_new(&sc[i]);
        test_handle(&sc[i]);
        test_sharp(&sc[i]);
        test_threads(&sc[i]);
    }
    test_surprise(4);
    test_surprise(2);
    (void)PI;
    return check_summary("filter_api");
}
