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
 */
#define _DEFAULT_SOURCE 1
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <unistd.h>

#include "check.h"

static const double PI = 3.14159265358979323846;

static unsigned char *guard_pages; /* [readable page][PROT_NONE page] */
static size_t page_size;

/* A copy of src[0..n) ending exactly at an inaccessible page: reading past n crashes. There is
 * one such buffer: pass at most one flush() result per call. */
static double *flush(const double *src, size_t n) {
    double *p = (double *)(guard_pages + page_size) - n;
    memcpy(p, src, n * sizeof(double));
    return p;
}

static double *no_access(void) { return (double *)(guard_pages + page_size); }

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

/* The state as raw bytes, for bit-for-bit comparisons. */
typedef struct {
    double m[16], z[4];
} snapshot;

static snapshot snap(const bingham_filter *f) {
    snapshot s;
    memset(&s, 0, sizeof s);
    if (bingham_filter_get_state(f, s.m, s.z) != BINGHAM_OK) {
        fprintf(stderr, "get_state failed\n");
        exit(1);
    }
    return s;
}

static int same(snapshot a, snapshot b) { return memcmp(&a, &b, sizeof a) == 0; }

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
    long ps = sysconf(_SC_PAGESIZE);
    page_size = ps > 0 ? (size_t)ps : 4096;
    guard_pages = mmap(NULL, 2 * page_size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS,
                       -1, 0);
    if (guard_pages == MAP_FAILED || mprotect(guard_pages + page_size, page_size, PROT_NONE)) {
        perror("mmap/mprotect");
        return 1;
    }
    sc[0] = scenario_2d();
    sc[1] = scenario_4d();
    for (i = 0; i < 2; ++i) {
        test_new(&sc[i]);
        test_handle(&sc[i]);
        test_sharp(&sc[i]);
        test_threads(&sc[i]);
    }
    (void)PI;
    return check_summary("filter_api");
}
