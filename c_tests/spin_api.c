/* The C API of the spin filter (bingham_spin_filter_*), function by function:
 *
 * - the success path of every function; arrays placed flush against an inaccessible page, so
 *   nothing is read beyond 4 (16) entries; a step without observation (y = NULL) reads neither
 *   m_o nor z_o (NULL, or aimed at the inaccessible page);
 * - lifecycle: new (a uniform orientation prior included), clone, free (of NULL too; the clone
 *   outlives its original), clones evolve bit for bit like the original and independently of it;
 * - get_state / set_state round trip (bit for bit), z sorted and shifted on the way in; the
 *   modes are the last columns of the marginals' M; the spreads are 2 sqrt(omega_i) and
 *   2 sqrt(1 - omega_3), omega from bingham_second_moment of the marginals;
 * - the error contract: every pointer argument NULL -> BINGHAM_ERR_NULL_ARGUMENT with a message
 *   naming the function and the argument; NaN and +-Inf in every entry of every input ->
 *   BINGHAM_ERR_INVALID_ARGUMENT naming the entry; u / y off unit length by 2e-3 (beyond
 *   BINGHAM_UNIT_TOL = 1e-3) or zero -> INVALID_ARGUMENT ("unit"), by 5e-4 accepted and
 *   normalized; matrices off orthogonality by 2e-6 -> INVALID_ARGUMENT ("orthogonal"), by 2e-7
 *   accepted; after every failure the state (get_state, bit for bit) unchanged, output buffers
 *   untouched, and a twin that saw only the successful calls still equal bit for bit (no hidden
 *   state, warm start or noise cache, was changed by a failure);
 * - hostile concentrations (+-1e300, -1e-300, uniform priors): a status, never a crash, and on
 *   error the state unchanged;
 * - threads: handles on different threads are independent, const functions run concurrently
 *   on one handle.
 *
 * The world-frame steps of the filter handle are tested in world_api.c; the helpers both use are
 * in api_util.h.
 */
#define _DEFAULT_SOURCE 1
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>

#include "check.h"
#include "api_util.h"

static const double I4[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

/* The Hamilton product a b (scalar first). */
static void qmul(const double *a, const double *b, double *r) {
    double t[4];
    t[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    t[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    t[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    t[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
    memcpy(r, t, sizeof t);
}

/* ---- the spin filter's state as raw bytes -------------------------------------------------- */

typedef struct {
    double mx[16], zx[4], mv[16], zv[4];
} spin_snapshot;

static spin_snapshot spin_snap(const bingham_spin_filter *f) {
    spin_snapshot s;
    memset(&s, 0, sizeof s);
    if (bingham_spin_filter_get_state(f, s.mx, s.zx, s.mv, s.zv) != BINGHAM_OK) {
        fprintf(stderr, "bingham_spin_filter_get_state failed\n");
        exit(1);
    }
    return s;
}

static int spin_same(spin_snapshot a, spin_snapshot b) { return memcmp(&a, &b, sizeof a) == 0; }

/* Expects `call` to fail with `expected`, the state of the spin filter `f` bit for bit unchanged
 * and the last message naming `fn` and containing `needle` (if not NULL). */
#define CHECK_SPIN_FAILS(f, call, expected, fn, needle)                                          \
    do {                                                                                         \
        spin_snapshot check_before_ = spin_snap(f);                                              \
        CHECK_STATUS(call, expected);                                                            \
        CHECK(spin_same(check_before_, spin_snap(f)));                                           \
        CHECK_MESSAGE(fn, needle);                                                               \
    } while (0)

/* ---- the spin filter's parameters ----------------------------------------------------------- */

typedef struct {
    double mx[16], zx[4], mv[16], zv[4], mw[16], zw[4], mo[16], zo[4], u[4], y[4];
} spin_params;

/* The a-th state array of q in the order of the arguments: m_x, z_x, m_v, z_v. */
static double *state_array(spin_params *q, size_t a) {
    return a == 0 ? q->mx : (a == 1 ? q->zx : (a == 2 ? q->mv : q->zv));
}

static spin_params params(void) {
    spin_params p;
    double zx[4] = {-5, -1, -3, 0}, zv[4] = {0, -3, -3, -3}, zw[4] = {0, -400, -400, -10},
           zo[4] = {0, -40, -40, -10}, axis[4] = {0.995, 0.05, -0.07, 0.03};
    fill_orthogonal(4, p.mx, 0.4);
    memcpy(p.mv, I4, sizeof p.mv);
    memcpy(p.mw, I4, sizeof p.mw);
    fill_orthogonal(4, p.mo, 1.1);
    memcpy(p.zx, zx, sizeof zx);
    memcpy(p.zv, zv, sizeof zv);
    memcpy(p.zw, zw, sizeof zw);
    memcpy(p.zo, zo, sizeof zo);
    normalize(axis, 4);
    memcpy(p.u, axis, sizeof axis);
    unit_vector(4, 0.7, p.y);
    return p;
}

/* ---- bingham_spin_filter_new / free / clone ------------------------------------------------ */

static void test_spin_new(void) {
    spin_params p = params();
    bingham_spin_filter *f = NULL, *sentinel = (bingham_spin_filter *)&p, *out = sentinel;
    double m[16], z[4], uniform[4] = {0, 0, 0, 0};
    const char *fn = "bingham_spin_filter_new";
    const char *names[4] = {"m_x", "z_x", "m_v", "z_v"};
    size_t i, k, a;

    /* success, each input read exactly to its end */
    CHECK_OK(bingham_spin_filter_new(flush(p.mx, 16), p.zx, p.mv, p.zv, &f));
    bingham_spin_filter_free(f);
    CHECK_OK(bingham_spin_filter_new(p.mx, flush(p.zx, 4), p.mv, p.zv, &f));
    bingham_spin_filter_free(f);
    CHECK_OK(bingham_spin_filter_new(p.mx, p.zx, flush(p.mv, 16), p.zv, &f));
    bingham_spin_filter_free(f);
    CHECK_OK(bingham_spin_filter_new(p.mx, p.zx, p.mv, flush(p.zv, 4), &f));
    /* the state: z sorted and shifted, the mode the column of the largest z */
    {
        spin_snapshot s = spin_snap(f);
        CHECK(s.zx[0] == -5 && s.zx[1] == -3 && s.zx[2] == -1 && s.zx[3] == 0);
        CHECK(s.zv[0] == -3 && s.zv[1] == -3 && s.zv[2] == -3 && s.zv[3] == 0);
        for (i = 0; i < 4; ++i) CHECK(fabs(fabs(s.mx[i * 4 + 3]) - fabs(p.mx[i * 4 + 3])) < 1e-15);
        CHECK(fabs(fabs(s.mv[3]) - 1) < 1e-15);
    }
    bingham_spin_filter_free(f);
    /* a uniform orientation prior and a uniform spin prior */
    CHECK_OK(bingham_spin_filter_new(I4, uniform, p.mv, p.zv, &f));
    CHECK_OK(bingham_spin_filter_step(f, NULL, p.mw, p.zw, p.y, p.mo, p.zo));
    bingham_spin_filter_free(f);
    CHECK_OK(bingham_spin_filter_new(I4, uniform, I4, uniform, &f));
    CHECK_OK(bingham_spin_filter_step(f, NULL, p.mw, p.zw, NULL, NULL, NULL));
    CHECK_OK(bingham_spin_filter_step(f, p.u, p.mw, p.zw, p.y, p.mo, p.zo));
    bingham_spin_filter_free(f);
    bingham_spin_filter_free(NULL);

    /* NULL arguments: named, *out untouched */
    for (a = 0; a < 5; ++a) {
        const double *in[4];
        in[0] = p.mx;
        in[1] = p.zx;
        in[2] = p.mv;
        in[3] = p.zv;
        if (a < 4) in[a] = NULL;
        CHECK_STATUS(bingham_spin_filter_new(in[0], in[1], in[2], in[3], a < 4 ? &out : NULL),
                     BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE(fn, null_needle(a < 4 ? names[a] : "out"));
        CHECK(out == sentinel);
    }
    /* NaN / +-Inf in every entry */
    for (a = 0; a < 4; ++a) {
        size_t n = (a % 2 == 0) ? 16 : 4;
        for (i = 0; i < n; ++i) {
            double bad[3] = {NAN, INFINITY, -INFINITY};
            for (k = 0; k < 3; ++k) {
                spin_params q = p;
                state_array(&q, a)[i] = bad[k];
                CHECK_STATUS(bingham_spin_filter_new(q.mx, q.zx, q.mv, q.zv, &out), BINGHAM_ERR_INVALID_ARGUMENT);
                CHECK_MESSAGE(fn, entry_needle(names[a], i));
                CHECK(out == sentinel);
            }
        }
    }
    /* orthogonality: 2e-6 off refused (naming the matrix), 2e-7 accepted */
    memcpy(m, p.mx, sizeof m);
    m[5] += 2e-6;
    CHECK_STATUS(bingham_spin_filter_new(m, p.zx, p.mv, p.zv, &out), BINGHAM_ERR_INVALID_ARGUMENT);
    CHECK_MESSAGE(fn, "`m_x` is not orthogonal");
    CHECK_STATUS(bingham_spin_filter_new(p.mx, p.zx, m, p.zv, &out), BINGHAM_ERR_INVALID_ARGUMENT);
    CHECK_MESSAGE(fn, "`m_v` is not orthogonal");
    CHECK(out == sentinel);
    m[5] = p.mx[5] + 2e-7;
    CHECK_OK(bingham_spin_filter_new(m, p.zx, p.mv, p.zv, &f));
    bingham_spin_filter_free(f);
    /* hostile but finite concentrations: a status, and a handle only on success */
    {
        const double hostile[][4] = {{0, -1e300, -1e300, -1e300}, {1e300, 0, 0, 0},   {-1e-300, 0, 0, 0},
                                     {1e300, -1e300, 0, 0},       {0, 0, -1e-300, 0}, {-1e13, -1e13, -1e13, 0}};
        for (k = 0; k < sizeof hostile / sizeof hostile[0]; ++k) {
            bingham_spin_filter *g = sentinel;
            int st;
            memcpy(z, hostile[k], sizeof z);
            st = bingham_spin_filter_new(I4, z, I4, z, &g);
            CHECK(st == BINGHAM_OK || st == BINGHAM_ERR_INVALID_ARGUMENT || st == BINGHAM_ERR_NUMERICAL);
            if (st == BINGHAM_OK) {
                spin_snapshot s = spin_snap(g);
                for (i = 0; i < 4; ++i) CHECK(isfinite(s.zx[i]) && isfinite(s.zv[i]));
                bingham_spin_filter_free(g);
            } else {
                CHECK(g == sentinel);
                CHECK_MESSAGE(fn, NULL);
            }
        }
    }
}

/* Clones evolve bit for bit like their original, independently of it, and outlive it. */
static void test_spin_clone(void) {
    spin_params p = params();
    bingham_spin_filter *f = NULL, *g = NULL, *h = NULL, *sentinel = (bingham_spin_filter *)&p, *out = sentinel;
    double y[4];
    int k;
    CHECK_OK(bingham_spin_filter_new(p.mx, p.zx, p.mv, p.zv, &f));
    CHECK_OK(bingham_spin_filter_step(f, p.u, p.mw, p.zw, p.y, p.mo, p.zo));
    CHECK_STATUS(bingham_spin_filter_clone(NULL, &out), BINGHAM_ERR_NULL_ARGUMENT);
    CHECK_MESSAGE("bingham_spin_filter_clone", "`f` is NULL");
    CHECK_STATUS(bingham_spin_filter_clone(f, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    CHECK_MESSAGE("bingham_spin_filter_clone", "`out` is NULL");
    CHECK(out == sentinel);
    CHECK_OK(bingham_spin_filter_clone(f, &g));
    CHECK(g != NULL && g != f);
    CHECK(spin_same(spin_snap(f), spin_snap(g)));
    for (k = 0; k < 15; ++k) {
        unit_vector(4, 0.2 * k, y);
        CHECK_OK(bingham_spin_filter_step(f, k % 2 ? p.u : NULL, p.mw, p.zw, k % 4 == 3 ? NULL : y, p.mo, p.zo));
        CHECK_OK(bingham_spin_filter_step(g, k % 2 ? p.u : NULL, p.mw, p.zw, k % 4 == 3 ? NULL : y, p.mo, p.zo));
    }
    CHECK(spin_same(spin_snap(f), spin_snap(g)));
    /* independence: a step of the clone leaves the original as it was, and vice versa */
    {
        spin_snapshot sf = spin_snap(f), sg;
        CHECK_OK(bingham_spin_filter_step(g, NULL, p.mw, p.zw, p.y, p.mo, p.zo));
        CHECK(spin_same(sf, spin_snap(f)));
        CHECK(!spin_same(sf, spin_snap(g)));
        sg = spin_snap(g);
        CHECK_OK(bingham_spin_filter_set_state(f, p.mx, p.zx, p.mv, p.zv));
        CHECK(spin_same(sg, spin_snap(g)));
    }
    /* the clone of a clone outlives both */
    CHECK_OK(bingham_spin_filter_clone(g, &h));
    bingham_spin_filter_free(g);
    bingham_spin_filter_free(f);
    CHECK_OK(bingham_spin_filter_step(h, NULL, p.mw, p.zw, p.y, p.mo, p.zo));
    bingham_spin_filter_free(h);
}

/* ---- bingham_spin_filter_step -------------------------------------------------------------- */

/* Every failing call goes to `f` only, every successful one to `f` and `twin` alike. */
static void test_spin_step(void) {
    spin_params p = params();
    bingham_spin_filter *f = NULL, *twin = NULL, *g = NULL;
    const char *fn = "bingham_spin_filter_step";
    size_t i, k, a;
    double v[16];

    CHECK_OK(bingham_spin_filter_new(p.mx, p.zx, p.mv, p.zv, &f));
    CHECK_OK(bingham_spin_filter_new(p.mx, p.zx, p.mv, p.zv, &twin));
#define BOTH_OK(call_f, call_twin)                                                              \
    do {                                                                                         \
        CHECK_OK(call_f);                                                                        \
        CHECK_OK(call_twin);                                                                     \
    } while (0)

    /* success, each input read exactly to its end */
    BOTH_OK(bingham_spin_filter_step(f, flush(p.u, 4), p.mw, p.zw, p.y, p.mo, p.zo),
            bingham_spin_filter_step(twin, p.u, p.mw, p.zw, p.y, p.mo, p.zo));
    BOTH_OK(bingham_spin_filter_step(f, p.u, flush(p.mw, 16), p.zw, p.y, p.mo, p.zo),
            bingham_spin_filter_step(twin, p.u, p.mw, p.zw, p.y, p.mo, p.zo));
    BOTH_OK(bingham_spin_filter_step(f, p.u, p.mw, flush(p.zw, 4), p.y, p.mo, p.zo),
            bingham_spin_filter_step(twin, p.u, p.mw, p.zw, p.y, p.mo, p.zo));
    BOTH_OK(bingham_spin_filter_step(f, p.u, p.mw, p.zw, flush(p.y, 4), p.mo, p.zo),
            bingham_spin_filter_step(twin, p.u, p.mw, p.zw, p.y, p.mo, p.zo));
    BOTH_OK(bingham_spin_filter_step(f, p.u, p.mw, p.zw, p.y, flush(p.mo, 16), p.zo),
            bingham_spin_filter_step(twin, p.u, p.mw, p.zw, p.y, p.mo, p.zo));
    BOTH_OK(bingham_spin_filter_step(f, p.u, p.mw, p.zw, p.y, p.mo, flush(p.zo, 4)),
            bingham_spin_filter_step(twin, p.u, p.mw, p.zw, p.y, p.mo, p.zo));
    /* u = NULL: no control */
    BOTH_OK(bingham_spin_filter_step(f, NULL, p.mw, p.zw, p.y, p.mo, p.zo),
            bingham_spin_filter_step(twin, NULL, p.mw, p.zw, p.y, p.mo, p.zo));
    /* y = NULL: m_o and z_o are not read (NULL, inaccessible, or invalid) */
    BOTH_OK(bingham_spin_filter_step(f, NULL, p.mw, p.zw, NULL, NULL, NULL),
            bingham_spin_filter_step(twin, NULL, p.mw, p.zw, NULL, NULL, NULL));
    {
        double nan_o[16];
        for (i = 0; i < 16; ++i) nan_o[i] = NAN;
        BOTH_OK(bingham_spin_filter_step(f, p.u, p.mw, p.zw, NULL, no_access(), no_access()),
                bingham_spin_filter_step(twin, p.u, p.mw, p.zw, NULL, NULL, NULL));
        BOTH_OK(bingham_spin_filter_step(f, NULL, p.mw, p.zw, NULL, nan_o, nan_o),
                bingham_spin_filter_step(twin, NULL, p.mw, p.zw, NULL, NULL, NULL));
    }
    CHECK(spin_same(spin_snap(f), spin_snap(twin)));
    /* a step without observation differs from one with */
    {
        spin_snapshot s0 = spin_snap(f);
        CHECK_OK(bingham_spin_filter_clone(f, &g));
        CHECK_OK(bingham_spin_filter_step(g, NULL, p.mw, p.zw, NULL, NULL, NULL));
        CHECK(!spin_same(s0, spin_snap(g)));
        bingham_spin_filter_free(g);
    }

    /* NULL arguments (m_o / z_o only with an observation) */
    {
        const char *names[6] = {"m_w", "z_w", "m_o", "z_o"};
        CHECK_SPIN_FAILS(f, bingham_spin_filter_step(NULL, p.u, p.mw, p.zw, p.y, p.mo, p.zo), BINGHAM_ERR_NULL_ARGUMENT,
                         fn, "`f` is NULL");
        for (a = 0; a < 4; ++a) {
            const double *mw = a == 0 ? NULL : p.mw, *zw = a == 1 ? NULL : p.zw, *mo = a == 2 ? NULL : p.mo,
                         *zo = a == 3 ? NULL : p.zo;
            CHECK_SPIN_FAILS(f, bingham_spin_filter_step(f, p.u, mw, zw, p.y, mo, zo), BINGHAM_ERR_NULL_ARGUMENT, fn,
                             null_needle(names[a]));
            if (a < 2)
                CHECK_SPIN_FAILS(f, bingham_spin_filter_step(f, NULL, mw, zw, NULL, NULL, NULL),
                                 BINGHAM_ERR_NULL_ARGUMENT, fn, null_needle(names[a]));
        }
    }
    /* NaN / +-Inf in every entry of every input */
    {
        const char *names[6] = {"u", "m_w", "z_w", "y", "m_o", "z_o"};
        const size_t lens[6] = {4, 16, 4, 4, 16, 4};
        for (a = 0; a < 6; ++a)
            for (i = 0; i < lens[a]; ++i)
                for (k = 0; k < 3; ++k) {
                    spin_params q = p;
                    double *arr[6];
                    double bad = k == 0 ? NAN : (k == 1 ? INFINITY : -INFINITY);
                    arr[0] = q.u;
                    arr[1] = q.mw;
                    arr[2] = q.zw;
                    arr[3] = q.y;
                    arr[4] = q.mo;
                    arr[5] = q.zo;
                    arr[a][i] = bad;
                    CHECK_SPIN_FAILS(f, bingham_spin_filter_step(f, q.u, q.mw, q.zw, q.y, q.mo, q.zo),
                                     BINGHAM_ERR_INVALID_ARGUMENT, fn, entry_needle(names[a], i));
                }
    }
    /* unit length: 2e-3 off (either way) or zero refused, 5e-4 off accepted and normalized */
    {
        double scale[3] = {1 + 2e-3, 1 - 2e-3, 0};
        for (k = 0; k < 3; ++k) {
            for (i = 0; i < 4; ++i) v[i] = p.u[i] * scale[k];
            CHECK_SPIN_FAILS(f, bingham_spin_filter_step(f, v, p.mw, p.zw, p.y, p.mo, p.zo),
                             BINGHAM_ERR_INVALID_ARGUMENT, fn, "`u` must be a unit vector");
            for (i = 0; i < 4; ++i) v[i] = p.y[i] * scale[k];
            CHECK_SPIN_FAILS(f, bingham_spin_filter_step(f, p.u, p.mw, p.zw, v, p.mo, p.zo),
                             BINGHAM_ERR_INVALID_ARGUMENT, fn, "`y` must be a unit vector");
        }
    }
    /* orthogonality */
    memcpy(v, I4, sizeof v);
    v[6] += 2e-6;
    CHECK_SPIN_FAILS(f, bingham_spin_filter_step(f, p.u, v, p.zw, p.y, p.mo, p.zo), BINGHAM_ERR_INVALID_ARGUMENT, fn,
                     "`m_w` is not orthogonal");
    CHECK_SPIN_FAILS(f, bingham_spin_filter_step(f, p.u, p.mw, p.zw, p.y, v, p.zo), BINGHAM_ERR_INVALID_ARGUMENT, fn,
                     "`m_o` is not orthogonal");
    /* a failure left no trace: the twin, which saw only the successful calls, is still equal */
    CHECK(spin_same(spin_snap(f), spin_snap(twin)));
    BOTH_OK(bingham_spin_filter_step(f, p.u, p.mw, p.zw, p.y, p.mo, p.zo),
            bingham_spin_filter_step(twin, p.u, p.mw, p.zw, p.y, p.mo, p.zo));
    CHECK(spin_same(spin_snap(f), spin_snap(twin)));

    /* within the tolerances: accepted, the vectors normalized (the same result as exact input) */
    CHECK_OK(bingham_spin_filter_clone(f, &g));
    {
        double u2[4], y2[4], m2[16];
        spin_snapshot a1, a2;
        for (i = 0; i < 4; ++i) {
            u2[i] = p.u[i] * (1 + 5e-4);
            y2[i] = -p.y[i] * (1 - 5e-4); /* the sign of y does not matter */
        }
        memcpy(m2, p.mw, sizeof m2);
        m2[6] += 2e-7;
        CHECK_OK(bingham_spin_filter_step(f, u2, m2, p.zw, y2, p.mo, p.zo));
        CHECK_OK(bingham_spin_filter_step(g, p.u, p.mw, p.zw, p.y, p.mo, p.zo));
        a1 = spin_snap(f);
        a2 = spin_snap(g);
        CHECK(exponent_difference(a1.mx, a1.zx, a2.mx, a2.zx) < 1e-9);
        CHECK(exponent_difference(a1.mv, a1.zv, a2.mv, a2.zv) < 1e-6); /* m_w off by 2e-7 */
    }
    bingham_spin_filter_free(g);
    bingham_spin_filter_free(twin);
    bingham_spin_filter_free(f);
#undef BOTH_OK
}

/* ---- log_likelihood, getters, set_state ---------------------------------------------------- */

static void test_spin_const_and_state(void) {
    spin_params p = params();
    bingham_spin_filter *f = NULL;
    double ll = 0, ll2 = 0, v[16];
    size_t i, k, a;
    spin_snapshot before;

    CHECK_OK(bingham_spin_filter_new(p.mx, p.zx, p.mv, p.zv, &f));
    CHECK_OK(bingham_spin_filter_step(f, p.u, p.mw, p.zw, p.y, p.mo, p.zo));
    before = spin_snap(f);

    /* log_likelihood: const, finite, sign-blind in y, output written only on success */
    {
        const char *fn = "bingham_spin_filter_log_likelihood";
        double ny[4];
        CHECK_OK(bingham_spin_filter_log_likelihood(f, flush(p.y, 4), p.mo, p.zo, &ll));
        CHECK(isfinite(ll));
        CHECK_OK(bingham_spin_filter_log_likelihood(f, p.y, flush(p.mo, 16), p.zo, &ll2));
        CHECK(ll2 == ll);
        CHECK_OK(bingham_spin_filter_log_likelihood(f, p.y, p.mo, flush(p.zo, 4), &ll2));
        CHECK(ll2 == ll);
        for (i = 0; i < 4; ++i) ny[i] = -p.y[i];
        CHECK_OK(bingham_spin_filter_log_likelihood(f, ny, p.mo, p.zo, &ll2));
        CHECK_CLOSE(ll2, ll, 1e-12);
        CHECK(spin_same(before, spin_snap(f)));
        ll2 = 12345.0;
        CHECK_STATUS(bingham_spin_filter_log_likelihood(NULL, p.y, p.mo, p.zo, &ll2), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE(fn, "`f` is NULL");
        CHECK_STATUS(bingham_spin_filter_log_likelihood(f, NULL, p.mo, p.zo, &ll2), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE(fn, "`y` is NULL");
        CHECK_STATUS(bingham_spin_filter_log_likelihood(f, p.y, NULL, p.zo, &ll2), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE(fn, "`m_o` is NULL");
        CHECK_STATUS(bingham_spin_filter_log_likelihood(f, p.y, p.mo, NULL, &ll2), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE(fn, "`z_o` is NULL");
        CHECK_STATUS(bingham_spin_filter_log_likelihood(f, p.y, p.mo, p.zo, NULL), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE(fn, "`log_l` is NULL");
        for (a = 0; a < 3; ++a) {
            const char *names[3] = {"y", "m_o", "z_o"};
            size_t n = a == 1 ? 16 : 4;
            for (i = 0; i < n; ++i) {
                spin_params q = p;
                double *arr[3];
                arr[0] = q.y;
                arr[1] = q.mo;
                arr[2] = q.zo;
                arr[a][i] = (i % 2) ? -INFINITY : NAN;
                CHECK_STATUS(bingham_spin_filter_log_likelihood(f, q.y, q.mo, q.zo, &ll2), BINGHAM_ERR_INVALID_ARGUMENT);
                CHECK_MESSAGE(fn, entry_needle(names[a], i));
            }
        }
        for (i = 0; i < 4; ++i) v[i] = p.y[i] * 1.002;
        CHECK_STATUS(bingham_spin_filter_log_likelihood(f, v, p.mo, p.zo, &ll2), BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK_MESSAGE(fn, "`y` must be a unit vector");
        memcpy(v, I4, sizeof v);
        v[9] -= 2e-6;
        CHECK_STATUS(bingham_spin_filter_log_likelihood(f, p.y, v, p.zo, &ll2), BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK_MESSAGE(fn, "`m_o` is not orthogonal");
        CHECK(ll2 == 12345.0);
        CHECK(spin_same(before, spin_snap(f)));
        /* a noise never used in a step (not cached) works as well, and leaves the state */
        {
            double zo2[4] = {-7, 0, -7, -2};
            CHECK_OK(bingham_spin_filter_log_likelihood(f, p.y, I4, zo2, &ll2));
            CHECK(isfinite(ll2) && ll2 != ll);
            CHECK(spin_same(before, spin_snap(f)));
        }
    }

    /* get_state: outputs only on success; the marginals normalized */
    {
        const char *fn = "bingham_spin_filter_get_state";
        double sm[40];
        spin_snapshot s = spin_snap(f);
        for (i = 0; i < 40; ++i) sm[i] = 777.0;
        CHECK_STATUS(bingham_spin_filter_get_state(NULL, sm, sm + 16, sm + 20, sm + 36), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE(fn, "`f` is NULL");
        CHECK_STATUS(bingham_spin_filter_get_state(f, NULL, sm + 16, sm + 20, sm + 36), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE(fn, "`m_x` is NULL");
        CHECK_STATUS(bingham_spin_filter_get_state(f, sm, NULL, sm + 20, sm + 36), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE(fn, "`z_x` is NULL");
        CHECK_STATUS(bingham_spin_filter_get_state(f, sm, sm + 16, NULL, sm + 36), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE(fn, "`m_v` is NULL");
        CHECK_STATUS(bingham_spin_filter_get_state(f, sm, sm + 16, sm + 20, NULL), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE(fn, "`z_v` is NULL");
        for (i = 0; i < 40; ++i) CHECK(sm[i] == 777.0);
        /* into buffers flush against the inaccessible page: exactly 16 and 4 entries written */
        {
            double *mx = no_access() - 16;
            CHECK_OK(bingham_spin_filter_get_state(f, mx, sm + 16, sm + 20, sm + 36));
            CHECK(memcmp(mx, s.mx, sizeof s.mx) == 0);
        }
        {
            double *zv = no_access() - 4;
            CHECK_OK(bingham_spin_filter_get_state(f, sm, sm + 16, sm + 20, zv));
            CHECK(memcmp(zv, s.zv, sizeof s.zv) == 0);
        }
        for (k = 0; k < 2; ++k) {
            const double *m = k ? s.mv : s.mx, *z = k ? s.zv : s.zx;
            int r, c, j;
            for (j = 0; j < 3; ++j) CHECK(z[j] <= z[j + 1]);
            CHECK(z[3] == 0.0);
            for (r = 0; r < 4; ++r)
                for (c = 0; c < 4; ++c) {
                    double dot = 0;
                    for (j = 0; j < 4; ++j) dot += m[j * 4 + r] * m[j * 4 + c];
                    CHECK(fabs(dot - (r == c ? 1.0 : 0.0)) < 1e-12);
                }
        }
    }

    /* modes: the last columns; spreads: from the marginals' second moments */
    {
        double q[4] = {0, 0, 0, 0}, xs[4], vs[4], s[16], sq[4] = {777, 777, 777, 777}, ss[8];
        spin_snapshot st = spin_snap(f);
        CHECK_OK(bingham_spin_filter_orientation_mode(f, flush(q, 4)));
        memcpy(q, no_access() - 4, sizeof q);
        for (i = 0; i < 4; ++i) CHECK(q[i] == st.mx[i * 4 + 3]);
        CHECK_OK(bingham_spin_filter_spin_mode(f, q));
        for (i = 0; i < 4; ++i) CHECK(q[i] == st.mv[i * 4 + 3]);
        CHECK_STATUS(bingham_spin_filter_orientation_mode(NULL, sq), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE("bingham_spin_filter_orientation_mode", "`f` is NULL");
        CHECK_STATUS(bingham_spin_filter_orientation_mode(f, NULL), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE("bingham_spin_filter_orientation_mode", "`q` is NULL");
        CHECK_STATUS(bingham_spin_filter_spin_mode(NULL, sq), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE("bingham_spin_filter_spin_mode", "`f` is NULL");
        CHECK_STATUS(bingham_spin_filter_spin_mode(f, NULL), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE("bingham_spin_filter_spin_mode", "`q` is NULL");
        for (i = 0; i < 4; ++i) CHECK(sq[i] == 777);

        CHECK_OK(bingham_spin_filter_angular_spread(f, xs, vs));
        for (k = 0; k < 2; ++k) {
            const double *m = k ? st.mv : st.mx, *z = k ? st.zv : st.zx, *sp = k ? vs : xs;
            double w[4];
            int j, r, c;
            CHECK_OK(bingham_second_moment(4, m, z, s));
            for (j = 0; j < 4; ++j) {
                w[j] = 0;
                for (r = 0; r < 4; ++r)
                    for (c = 0; c < 4; ++c) w[j] += m[r * 4 + j] * s[r * 4 + c] * m[c * 4 + j];
            }
            for (j = 0; j < 3; ++j) CHECK_CLOSE(sp[j], 2 * sqrt(w[j]), 1e-9);
            CHECK_CLOSE(sp[3], 2 * sqrt(1 - w[3]), 1e-9);
            CHECK_CLOSE(sp[3] * sp[3], sp[0] * sp[0] + sp[1] * sp[1] + sp[2] * sp[2], 1e-12);
        }
        for (i = 0; i < 8; ++i) ss[i] = 777;
        CHECK_STATUS(bingham_spin_filter_angular_spread(NULL, ss, ss + 4), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE("bingham_spin_filter_angular_spread", "`f` is NULL");
        CHECK_STATUS(bingham_spin_filter_angular_spread(f, NULL, ss + 4), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE("bingham_spin_filter_angular_spread", "`x_spread` is NULL");
        CHECK_STATUS(bingham_spin_filter_angular_spread(f, ss, NULL), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE("bingham_spin_filter_angular_spread", "`v_spread` is NULL");
        for (i = 0; i < 8; ++i) CHECK(ss[i] == 777);
        CHECK(spin_same(before, spin_snap(f)));
    }

    /* set_state: round trip bit for bit; any order and shift in; errors change nothing */
    {
        const char *fn = "bingham_spin_filter_set_state";
        const char *names[4] = {"m_x", "z_x", "m_v", "z_v"};
        spin_snapshot s = spin_snap(f), s2;
        double zx[4] = {3, 1, 2, 4}, zv[4] = {10, 10, 10, 12};
        bingham_spin_filter *g = NULL;
        CHECK_OK(bingham_spin_filter_new(I4, zx, I4, zv, &g));
        CHECK_OK(bingham_spin_filter_set_state(g, s.mx, s.zx, s.mv, s.zv));
        CHECK(spin_same(s, spin_snap(g)));
        /* the same state gives the same steps (the warm start is only a starting point) */
        CHECK_OK(bingham_spin_filter_step(f, p.u, p.mw, p.zw, p.y, p.mo, p.zo));
        CHECK_OK(bingham_spin_filter_step(g, p.u, p.mw, p.zw, p.y, p.mo, p.zo));
        s = spin_snap(f);
        s2 = spin_snap(g);
        CHECK(exponent_difference(s.mx, s.zx, s2.mx, s2.zx) < 1e-9);
        CHECK(exponent_difference(s.mv, s.zv, s2.mv, s2.zv) < 1e-9);
        bingham_spin_filter_free(g);
        CHECK_OK(bingham_spin_filter_set_state(f, flush(I4, 16), zx, p.mv, zv));
        s = spin_snap(f);
        CHECK(s.zx[0] == -3 && s.zx[1] == -2 && s.zx[2] == -1 && s.zx[3] == 0);
        CHECK(s.zv[0] == -2 && s.zv[1] == -2 && s.zv[2] == -2 && s.zv[3] == 0);
        CHECK(fabs(fabs(s.mx[3 * 4 + 3]) - 1) < 1e-15); /* the mode: column 3 (z = 4) */
        CHECK_OK(bingham_spin_filter_set_state(f, p.mx, flush(p.zx, 4), p.mv, p.zv));
        CHECK_OK(bingham_spin_filter_set_state(f, p.mx, p.zx, flush(p.mv, 16), p.zv));
        CHECK_OK(bingham_spin_filter_set_state(f, p.mx, p.zx, p.mv, flush(p.zv, 4)));
        CHECK_SPIN_FAILS(f, bingham_spin_filter_set_state(NULL, p.mx, p.zx, p.mv, p.zv), BINGHAM_ERR_NULL_ARGUMENT, fn,
                         "`f` is NULL");
        for (a = 0; a < 4; ++a) {
            const double *in[4];
            in[0] = I4;
            in[1] = zx;
            in[2] = I4;
            in[3] = zv;
            in[a] = NULL;
            CHECK_SPIN_FAILS(f, bingham_spin_filter_set_state(f, in[0], in[1], in[2], in[3]), BINGHAM_ERR_NULL_ARGUMENT,
                             fn, null_needle(names[a]));
            for (i = 0; i < (a % 2 ? 4u : 16u); ++i) {
                spin_params q = p;
                state_array(&q, a)[i] = (i % 3 == 0) ? NAN : ((i % 3 == 1) ? INFINITY : -INFINITY);
                CHECK_SPIN_FAILS(f, bingham_spin_filter_set_state(f, q.mx, q.zx, q.mv, q.zv),
                                 BINGHAM_ERR_INVALID_ARGUMENT, fn, entry_needle(names[a], i));
            }
        }
        memcpy(v, I4, sizeof v);
        v[1] = 1e-5;
        CHECK_SPIN_FAILS(f, bingham_spin_filter_set_state(f, v, zx, I4, zv), BINGHAM_ERR_INVALID_ARGUMENT, fn,
                         "`m_x` is not orthogonal");
        CHECK_SPIN_FAILS(f, bingham_spin_filter_set_state(f, I4, zx, v, zv), BINGHAM_ERR_INVALID_ARGUMENT, fn,
                         "`m_v` is not orthogonal");
    }
    bingham_spin_filter_free(f);
}

/* Hostile concentrations in the noises and the state: a documented status, never a crash; on
 * error the state unchanged and the message naming the function. */
static void test_spin_hostile(void) {
    spin_params p = params();
    const double zs[][4] = {{0, -1e300, -1e300, -1e300}, {0, 1e300, 1e300, 1e300}, {-1e-300, 0, 0, 0},
                            {0, 0, 0, 0},                {0, -1e13, -1e13, -1e13}, {1e300, -1e300, 0, 0}};
    size_t n = sizeof zs / sizeof zs[0], a, b, k;
    for (a = 0; a < n; ++a)
        for (b = 0; b < n; ++b) {
            bingham_spin_filter *f = NULL;
            int st = bingham_spin_filter_new(I4, zs[a], p.mv, zs[b], &f);
            if (st != BINGHAM_OK) {
                CHECK(st == BINGHAM_ERR_INVALID_ARGUMENT || st == BINGHAM_ERR_NUMERICAL);
                CHECK_MESSAGE("bingham_spin_filter_new", NULL);
                continue;
            }
            for (k = 0; k < n; ++k) {
                spin_snapshot s = spin_snap(f);
                double ll = 12345.0, xs[4], vs[4];
                st = bingham_spin_filter_step(f, p.u, I4, zs[k], p.y, I4, zs[(k + a) % n]);
                CHECK(st == BINGHAM_OK || st == BINGHAM_ERR_INVALID_ARGUMENT || st == BINGHAM_ERR_NUMERICAL ||
                      st == BINGHAM_ERR_NOT_CONVERGED);
                if (st != BINGHAM_OK) {
                    CHECK(spin_same(s, spin_snap(f)));
                    CHECK_MESSAGE("bingham_spin_filter_step", NULL);
                } else {
                    spin_snapshot t = spin_snap(f);
                    int i;
                    for (i = 0; i < 4; ++i) CHECK(isfinite(t.zx[i]) && isfinite(t.zv[i]) && t.zx[3] == 0 && t.zv[3] == 0);
                }
                st = bingham_spin_filter_log_likelihood(f, p.y, I4, zs[k], &ll);
                CHECK(st == BINGHAM_OK || st == BINGHAM_ERR_INVALID_ARGUMENT || st == BINGHAM_ERR_NUMERICAL ||
                      st == BINGHAM_ERR_NOT_CONVERGED);
                CHECK(st == BINGHAM_OK ? isfinite(ll) : ll == 12345.0);
                st = bingham_spin_filter_angular_spread(f, xs, vs);
                CHECK(st == BINGHAM_OK || st == BINGHAM_ERR_NUMERICAL);
                st = bingham_spin_filter_step(f, NULL, I4, zs[k], NULL, NULL, NULL);
                CHECK(st == BINGHAM_OK || st == BINGHAM_ERR_INVALID_ARGUMENT || st == BINGHAM_ERR_NUMERICAL ||
                      st == BINGHAM_ERR_NOT_CONVERGED);
            }
            bingham_spin_filter_free(f);
        }
}

/* ---- threads ------------------------------------------------------------------------------ */

typedef struct {
    const bingham_spin_filter *shared;
    spin_snapshot result;
    double ll;
    int ok;
} job;

static void run_steps(bingham_spin_filter *f, int *ok) {
    spin_params p = params();
    double x[4] = {1, 0, 0, 0}, spin[4] = {0.9, 0.3, -0.2, 0.1}, y[4];
    int k;
    normalize(spin, 4);
    for (k = 0; k < 60; ++k) {
        qmul(spin, x, x);
        memcpy(y, x, sizeof y);
        *ok &= bingham_spin_filter_step(f, NULL, p.mw, p.zw, k % 5 == 4 ? NULL : y, p.mo, p.zo) == BINGHAM_OK;
    }
}

static void *thread_main(void *arg) {
    job *j = (job *)arg;
    spin_params p = params();
    bingham_spin_filter *f = NULL;
    int k;
    j->ok = bingham_spin_filter_new(p.mx, p.zx, p.mv, p.zv, &f) == BINGHAM_OK;
    if (!j->ok) return NULL;
    run_steps(f, &j->ok);
    j->result = spin_snap(f);
    bingham_spin_filter_free(f);
    for (k = 0; k < 50; ++k)
        j->ok &= bingham_spin_filter_log_likelihood(j->shared, p.y, p.mo, p.zo, &j->ll) == BINGHAM_OK;
    return NULL;
}

static void test_threads(void) {
    enum { T = 4 };
    spin_params p = params();
    pthread_t th[T];
    job jobs[T];
    bingham_spin_filter *ref = NULL, *shared = NULL;
    double ll;
    int ok = 1, t;
    spin_snapshot expect;
    CHECK_OK(bingham_spin_filter_new(p.mx, p.zx, p.mv, p.zv, &ref));
    run_steps(ref, &ok);
    CHECK(ok);
    expect = spin_snap(ref);
    CHECK_OK(bingham_spin_filter_new(p.mx, p.zx, p.mv, p.zv, &shared));
    CHECK_OK(bingham_spin_filter_log_likelihood(shared, p.y, p.mo, p.zo, &ll));
    for (t = 0; t < T; ++t) {
        jobs[t].shared = shared;
        CHECK(pthread_create(&th[t], NULL, thread_main, &jobs[t]) == 0);
    }
    for (t = 0; t < T; ++t) {
        CHECK(pthread_join(th[t], NULL) == 0);
        CHECK(jobs[t].ok);
        CHECK(spin_same(jobs[t].result, expect));
        CHECK(jobs[t].ll == ll);
    }
    bingham_spin_filter_free(shared);
    bingham_spin_filter_free(ref);
}

int main(void) {
    if (guard_pages_init()) return 1;
    test_spin_new();
    test_spin_clone();
    test_spin_step();
    test_spin_const_and_state();
    test_spin_hostile();
    test_threads();
    return check_summary("spin_api");
}
