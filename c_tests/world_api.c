/* The C API of the world-frame steps of the filter handle (bingham_filter_predict_world,
 * _update_world, _log_likelihood_world), for d = 2 and d = 4:
 *
 * - the success path of every function; arrays placed flush against an inaccessible page, so
 *   nothing is read beyond d (d*d) entries; u = NULL (no control) in predict_world; the sign of
 *   y does not matter;
 * - the error contract: every pointer argument NULL -> BINGHAM_ERR_NULL_ARGUMENT with a message
 *   naming the function and the argument; NaN and +-Inf in every entry of every input ->
 *   BINGHAM_ERR_INVALID_ARGUMENT naming the entry; u / y off unit length by 2e-3 (beyond
 *   BINGHAM_UNIT_TOL = 1e-3) or zero -> INVALID_ARGUMENT ("unit"), by 5e-4 accepted and
 *   normalized; matrices off orthogonality by 2e-6 -> INVALID_ARGUMENT ("orthogonal"), by 2e-7
 *   accepted; after every failure the state (get_state, bit for bit) unchanged, and a twin that
 *   saw only the successful calls still equal bit for bit; log_likelihood_world leaves the state
 *   and writes its output only on success;
 * - hostile concentrations (+-1e300, -1e-300, uniform): a status, never a crash, and on error
 *   the state unchanged.
 *
 * The spin filter's C API is tested in spin_api.c; the helpers both use are in api_util.h.
 */
#define _DEFAULT_SOURCE 1
#include <stdlib.h>

#include "check.h"
#include "api_util.h"

/* Expects `call` to fail with `expected`, the state of the filter `f` bit for bit unchanged and
 * the last message naming `fn` and containing `needle` (if not NULL). */
#define CHECK_FILTER_FAILS(f, call, expected, fn, needle)                                        \
    do {                                                                                         \
        snapshot check_before_ = snap(f);                                                        \
        CHECK_STATUS(call, expected);                                                            \
        CHECK(same(check_before_, snap(f)));                                                     \
        CHECK_MESSAGE(fn, needle);                                                               \
    } while (0)

/* The inputs of a world-frame step (a vector of d, a d x d matrix, a vector of d: arrays of 4,
 * 16, 4) with entry i of their concatenation replaced by a bad value: bad[0] in the first vector,
 * bad[1] in the matrix, bad[2] in the last one; `needle` names that entry ("`m_w[3]`"). */
typedef struct {
    double v[4], m[16], z[4];
    char needle[64];
} bad_inputs;

static bad_inputs bad_entry(size_t d, size_t i, const double *v, const double *m, const double *z,
                            const double bad[3], const char *const names[3]) {
    bad_inputs b;
    size_t dd = d * d;
    memcpy(b.v, v, sizeof b.v);
    memcpy(b.m, m, sizeof b.m);
    memcpy(b.z, z, sizeof b.z);
    if (i < d)
        b.v[i] = bad[0];
    else if (i < d + dd)
        b.m[i - d] = bad[1];
    else
        b.z[i - d - dd] = bad[2];
    strcpy(b.needle, i < d ? entry_needle(names[0], i)
                           : (i < d + dd ? entry_needle(names[1], i - d) : entry_needle(names[2], i - d - dd)));
    return b;
}

/* ---- the world-frame steps of the filter handle ------------------------------------------ */

static void test_world_steps(size_t d) {
    size_t dd = d * d, i, k;
    double m0[16], z0[4] = {-1, -4, -2, 0}, mw[16], zw[4] = {0, -200, -200, -10}, mv[16],
                   zv[4] = {0, -40, -40, -10}, u[4], y[4], bad[16], vv[4], ll = 0, ll2;
    bingham_filter *f = NULL, *twin = NULL;
    snapshot a_now;
    fill_orthogonal(d, m0, 0.2);
    memset(mw, 0, sizeof mw);
    for (i = 0; i < d; ++i) mw[i * d + i] = 1.0; /* identity mode: column 0 */
    fill_orthogonal(d, mv, 0.9);
    if (d == 2) {
        z0[0] = -3;
        z0[1] = 0;
        zw[1] = -50;
        zv[1] = -30;
    }
    unit_vector(d, 0.4, u);
    unit_vector(d, 1.9, y);
    CHECK_OK(bingham_filter_new(d, m0, z0, &f));
    CHECK_OK(bingham_filter_new(d, m0, z0, &twin));

    /* predict_world: success (u flush, NULL), every NULL, NaN/Inf, unit length, orthogonality */
    {
        const char *fn = "bingham_filter_predict_world";
        CHECK_OK(bingham_filter_predict_world(f, flush(u, d), mw, zw));
        CHECK_OK(bingham_filter_predict_world(f, u, flush(mw, dd), zw));
        CHECK_OK(bingham_filter_predict_world(f, NULL, mw, flush(zw, d)));
        CHECK_OK(bingham_filter_predict_world(twin, u, mw, zw));
        CHECK_OK(bingham_filter_predict_world(twin, u, mw, zw));
        CHECK_OK(bingham_filter_predict_world(twin, NULL, mw, zw));
        CHECK_FILTER_FAILS(f, bingham_filter_predict_world(NULL, u, mw, zw), BINGHAM_ERR_NULL_ARGUMENT, fn, "`f` is NULL");
        CHECK_FILTER_FAILS(f, bingham_filter_predict_world(f, u, NULL, zw), BINGHAM_ERR_NULL_ARGUMENT, fn, "`m_w` is NULL");
        CHECK_FILTER_FAILS(f, bingham_filter_predict_world(f, u, mw, NULL), BINGHAM_ERR_NULL_ARGUMENT, fn, "`z_w` is NULL");
        CHECK_FILTER_FAILS(f, bingham_filter_predict_world(f, NULL, NULL, zw), BINGHAM_ERR_NULL_ARGUMENT, fn,
                           "`m_w` is NULL");
        for (i = 0; i < d + dd + d; ++i) {
            const double bad_values[3] = {NAN, INFINITY, -INFINITY};
            const char *const names[3] = {"u", "m_w", "z_w"};
            bad_inputs b = bad_entry(d, i, u, mw, zw, bad_values, names);
            CHECK_FILTER_FAILS(f, bingham_filter_predict_world(f, b.v, b.m, b.z), BINGHAM_ERR_INVALID_ARGUMENT, fn,
                               b.needle);
        }
        for (k = 0; k < 3; ++k) {
            double s = k == 0 ? 1 + 2e-3 : (k == 1 ? 1 - 2e-3 : 0);
            for (i = 0; i < d; ++i) vv[i] = u[i] * s;
            CHECK_FILTER_FAILS(f, bingham_filter_predict_world(f, vv, mw, zw), BINGHAM_ERR_INVALID_ARGUMENT, fn,
                               "`u` must be a unit vector");
        }
        memcpy(bad, mw, sizeof bad);
        bad[1] += 2e-6;
        CHECK_FILTER_FAILS(f, bingham_filter_predict_world(f, u, bad, zw), BINGHAM_ERR_INVALID_ARGUMENT, fn,
                           "`m_w` is not orthogonal");
        CHECK(same(snap(f), snap(twin)));
        /* within the tolerances: accepted, u normalized */
        for (i = 0; i < d; ++i) vv[i] = u[i] * (1 + 5e-4);
        bad[1] = mw[1] + 2e-7;
        CHECK_OK(bingham_filter_predict_world(f, vv, bad, zw));
        CHECK_OK(bingham_filter_predict_world(twin, u, bad, zw));
        {
            snapshot a = snap(f), b = snap(twin);
            if (d == 4) CHECK(exponent_difference(a.m, a.z, b.m, b.z) < 1e-9);
        }
        a_now = snap(f);
        CHECK_OK(bingham_filter_set_state(twin, a_now.m, a_now.z));
    }

    /* update_world */
    {
        const char *fn = "bingham_filter_update_world";
        snapshot s;
        CHECK_OK(bingham_filter_update_world(f, flush(y, d), mv, zv));
        CHECK_OK(bingham_filter_update_world(f, y, flush(mv, dd), zv));
        CHECK_OK(bingham_filter_update_world(f, y, mv, flush(zv, d)));
        for (k = 0; k < 3; ++k) CHECK_OK(bingham_filter_update_world(twin, y, mv, zv));
        CHECK(same(snap(f), snap(twin)));
        CHECK_FILTER_FAILS(f, bingham_filter_update_world(NULL, y, mv, zv), BINGHAM_ERR_NULL_ARGUMENT, fn, "`f` is NULL");
        CHECK_FILTER_FAILS(f, bingham_filter_update_world(f, NULL, mv, zv), BINGHAM_ERR_NULL_ARGUMENT, fn, "`y` is NULL");
        CHECK_FILTER_FAILS(f, bingham_filter_update_world(f, y, NULL, zv), BINGHAM_ERR_NULL_ARGUMENT, fn, "`m_v` is NULL");
        CHECK_FILTER_FAILS(f, bingham_filter_update_world(f, y, mv, NULL), BINGHAM_ERR_NULL_ARGUMENT, fn, "`z_v` is NULL");
        for (i = 0; i < d + dd + d; ++i) {
            const double bad_values[3] = {-INFINITY, NAN, INFINITY};
            const char *const names[3] = {"y", "m_v", "z_v"};
            bad_inputs b = bad_entry(d, i, y, mv, zv, bad_values, names);
            CHECK_FILTER_FAILS(f, bingham_filter_update_world(f, b.v, b.m, b.z), BINGHAM_ERR_INVALID_ARGUMENT, fn,
                               b.needle);
        }
        for (k = 0; k < 3; ++k) {
            double sc = k == 0 ? 1 + 2e-3 : (k == 1 ? 1 - 2e-3 : 0);
            for (i = 0; i < d; ++i) vv[i] = y[i] * sc;
            CHECK_FILTER_FAILS(f, bingham_filter_update_world(f, vv, mv, zv), BINGHAM_ERR_INVALID_ARGUMENT, fn,
                               "`y` must be a unit vector");
        }
        memcpy(bad, mv, sizeof bad);
        bad[dd - 1] -= 2e-6;
        CHECK_FILTER_FAILS(f, bingham_filter_update_world(f, y, bad, zv), BINGHAM_ERR_INVALID_ARGUMENT, fn,
                           "`m_v` is not orthogonal");
        /* the sign of y does not matter; within the tolerance accepted */
        s = snap(f);
        for (i = 0; i < d; ++i) vv[i] = -y[i] * (1 - 5e-4);
        CHECK_OK(bingham_filter_update_world(f, vv, mv, zv));
        CHECK_OK(bingham_filter_update_world(twin, y, mv, zv));
        {
            snapshot a = snap(f), b = snap(twin);
            if (d == 4) CHECK(exponent_difference(a.m, a.z, b.m, b.z) < 1e-10);
            CHECK(!same(a, s));
        }
        a_now = snap(f);
        CHECK_OK(bingham_filter_set_state(twin, a_now.m, a_now.z));
    }

    /* log_likelihood_world: const, output written only on success */
    {
        const char *fn = "bingham_filter_log_likelihood_world";
        snapshot before = snap(f);
        CHECK_OK(bingham_filter_log_likelihood_world(f, flush(y, d), mv, zv, &ll));
        CHECK(isfinite(ll));
        CHECK_OK(bingham_filter_log_likelihood_world(f, y, flush(mv, dd), zv, &ll2));
        CHECK(ll2 == ll);
        CHECK_OK(bingham_filter_log_likelihood_world(f, y, mv, flush(zv, d), &ll2));
        CHECK(ll2 == ll);
        for (i = 0; i < d; ++i) vv[i] = -y[i];
        CHECK_OK(bingham_filter_log_likelihood_world(f, vv, mv, zv, &ll2));
        CHECK_CLOSE(ll2, ll, 1e-12);
        CHECK(same(before, snap(f)));
        ll2 = 12345.0;
        CHECK_STATUS(bingham_filter_log_likelihood_world(NULL, y, mv, zv, &ll2), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE(fn, "`f` is NULL");
        CHECK_STATUS(bingham_filter_log_likelihood_world(f, NULL, mv, zv, &ll2), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE(fn, "`y` is NULL");
        CHECK_STATUS(bingham_filter_log_likelihood_world(f, y, NULL, zv, &ll2), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE(fn, "`m_v` is NULL");
        CHECK_STATUS(bingham_filter_log_likelihood_world(f, y, mv, NULL, &ll2), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE(fn, "`z_v` is NULL");
        CHECK_STATUS(bingham_filter_log_likelihood_world(f, y, mv, zv, NULL), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE(fn, "`log_l` is NULL");
        for (i = 0; i < d + dd + d; ++i) {
            const double bad_values[3] = {NAN, -INFINITY, NAN};
            const char *const names[3] = {"y", "m_v", "z_v"};
            bad_inputs b = bad_entry(d, i, y, mv, zv, bad_values, names);
            CHECK_STATUS(bingham_filter_log_likelihood_world(f, b.v, b.m, b.z, &ll2), BINGHAM_ERR_INVALID_ARGUMENT);
            CHECK_MESSAGE(fn, b.needle);
        }
        for (i = 0; i < d; ++i) vv[i] = y[i] * 1.01;
        CHECK_STATUS(bingham_filter_log_likelihood_world(f, vv, mv, zv, &ll2), BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK_MESSAGE(fn, "`y` must be a unit vector");
        CHECK_STATUS(bingham_filter_log_likelihood_world(f, y, bad, zv, &ll2), BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK_MESSAGE(fn, "`m_v` is not orthogonal");
        CHECK(ll2 == 12345.0);
        CHECK(same(before, snap(f)));
    }

    /* hostile concentrations: a status; on error the state unchanged */
    {
        const double zs[][4] = {{0, -1e300, -1e300, -1e300}, {1e300, 0, 0, 0}, {-1e-300, 0, 0, 0},
                                {0, 0, 0, 0},                {1e300, -1e300, 0, 0}};
        for (k = 0; k < sizeof zs / sizeof zs[0]; ++k) {
            double z[4];
            snapshot s;
            int st;
            memcpy(z, zs[k], sizeof z);
            if (d == 2) z[1] = zs[k][1] != 0 ? zs[k][1] : zs[k][3];
            s = snap(f);
            st = bingham_filter_predict_world(f, u, mw, z);
            CHECK(st == BINGHAM_OK || st == BINGHAM_ERR_NUMERICAL || st == BINGHAM_ERR_NOT_CONVERGED ||
                  st == BINGHAM_ERR_INVALID_ARGUMENT);
            if (st != BINGHAM_OK) {
                CHECK(same(s, snap(f)));
                CHECK_MESSAGE("bingham_filter_predict_world", NULL);
            }
            s = snap(f);
            st = bingham_filter_update_world(f, y, mv, z);
            CHECK(st == BINGHAM_OK || st == BINGHAM_ERR_NUMERICAL || st == BINGHAM_ERR_INVALID_ARGUMENT);
            if (st != BINGHAM_OK) {
                CHECK(same(s, snap(f)));
                CHECK_MESSAGE("bingham_filter_update_world", NULL);
            }
            ll2 = 12345.0;
            st = bingham_filter_log_likelihood_world(f, y, mv, z, &ll2);
            CHECK(st == BINGHAM_OK ? isfinite(ll2) : ll2 == 12345.0);
            /* back to a moderate state */
            CHECK_OK(bingham_filter_set_state(f, m0, z0));
        }
    }
    bingham_filter_free(twin);
    bingham_filter_free(f);
}

int main(void) {
    if (guard_pages_init()) return 1;
    test_world_steps(2);
    test_world_steps(4);
    return check_summary("world_api");
}
