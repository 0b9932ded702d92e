/* The C API's error model, checked function by function from C:
 *
 * - the success path of every function (d = 2, 3, 4, 7 where supported);
 * - every required pointer set to NULL -> BINGHAM_ERR_NULL_ARGUMENT, optional ones accepted;
 * - NaN and +-Inf in every input array -> BINGHAM_ERR_INVALID_ARGUMENT;
 * - d = 0, 1, 65 -> BINGHAM_ERR_INVALID_DIMENSION, with every array pointer aimed at an
 *   inaccessible (PROT_NONE) page, so any read or write before the check would crash;
 * - d = 3 for the d = 2/4-only functions;
 * - non-orthogonal M and non-unit vectors just outside / inside the 1e-6 tolerances;
 * - after every failure: all output buffers byte-for-byte unchanged (sentinel fill), and a last
 *   error message that names the function and the offending argument;
 * - bingham_last_error_message (length query, truncation, NULL handling, per-thread),
 *   bingham_status_str for every code, bingham_version against the header macros;
 * - special cases: F overflow, degenerate second moments, n = 0, sampling determinism;
 * - deterministic samples (count, capacity, scheme, lambda) and the nonlinear filter steps
 *   (NULL handle / callback / noise, invalid noise before any callback, failing callbacks).
 */
#define _DEFAULT_SOURCE 1
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>

#include "check.h"
#include "api_util.h"

#define NS 9 /* number of points/samples used in the table-driven tests (> max d used) */

enum kind { K_NONE, K_M, K_Z, K_S, K_X, K_W, K_U, K_ONE, K_D, K_DD, K_N, K_ND };

typedef struct {
    size_t d, n;
    uint64_t seed;
    const double *in[4];
    double *out[3];
} call_t;

typedef bingham_status (*call_fn)(const call_t *);

typedef struct {
    const char *name;
    call_fn call;
    int only_2_4; /* composition and rotations */
    int in_kind[4];
    const char *in_name[4];
    int in_optional[4];
    int out_kind[3];
    const char *out_name[3];
    int out_optional[3];
} fn_t;

/* ---- thin wrappers with one uniform signature ------------------------------------------- */

static bingham_status c_nc(const call_t *c) {
    return bingham_normalization_constant(c->d, c->in[0], c->out[0], c->out[1]);
}
static bingham_status c_lnc(const call_t *c) {
    return bingham_log_normalization_constant(c->d, c->in[0], c->out[0], c->out[1]);
}
static bingham_status c_lnc_sp(const call_t *c) {
    return bingham_log_normalization_constant_saddlepoint(c->d, c->in[0], c->out[0], c->out[1]);
}
static bingham_status c_hess(const call_t *c) {
    return bingham_log_normalization_hessian(c->d, c->in[0], c->out[0], c->out[1], c->out[2]);
}
static bingham_status c_sm(const call_t *c) {
    return bingham_second_moment(c->d, c->in[0], c->in[1], c->out[0]);
}
static bingham_status c_mle(const call_t *c) {
    return bingham_mle(c->d, c->in[0], c->out[0], c->out[1]);
}
static bingham_status c_mles(const call_t *c) {
    return bingham_mle_samples(c->d, c->n, c->in[0], c->in[1], c->out[0], c->out[1]);
}
static bingham_status c_mul(const call_t *c) {
    return bingham_multiply(c->d, c->in[0], c->in[1], c->in[2], c->in[3], c->out[0], c->out[1]);
}
static bingham_status c_comp(const call_t *c) {
    return bingham_compose(c->d, c->in[0], c->in[1], c->in[2], c->in[3], c->out[0], c->out[1]);
}
static bingham_status c_pdf(const call_t *c) {
    return bingham_pdf(c->d, c->in[0], c->in[1], c->n, c->in[2], c->out[0]);
}
static bingham_status c_lpdf(const call_t *c) {
    return bingham_log_pdf(c->d, c->in[0], c->in[1], c->n, c->in[2], c->out[0]);
}
static bingham_status c_ent(const call_t *c) {
    return bingham_entropy(c->d, c->in[0], c->in[1], c->out[0]);
}
static bingham_status c_kl(const call_t *c) {
    return bingham_kl_divergence(c->d, c->in[0], c->in[1], c->in[2], c->in[3], c->out[0]);
}
static bingham_status c_samp(const call_t *c) {
    return bingham_sample(c->d, c->in[0], c->in[1], c->seed, c->n, c->out[0]);
}
static bingham_status c_rotl(const call_t *c) {
    return bingham_rotate_left(c->d, c->in[0], c->in[1], c->in[2], c->out[0], c->out[1]);
}
static bingham_status c_rotr(const call_t *c) {
    return bingham_rotate_right(c->d, c->in[0], c->in[1], c->in[2], c->out[0], c->out[1]);
}
static bingham_status c_mode(const call_t *c) {
    return bingham_mode(c->d, c->in[0], c->in[1], c->out[0]);
}

static const fn_t FUNCTIONS[] = {
    {"bingham_normalization_constant", c_nc, 0, {K_Z}, {"z"}, {0}, {K_ONE, K_D}, {"f", "df"}, {0, 1}},
    {"bingham_log_normalization_constant", c_lnc, 0, {K_Z}, {"z"}, {0}, {K_ONE, K_D},
     {"log_f", "dlog_f"}, {0, 1}},
    {"bingham_log_normalization_constant_saddlepoint", c_lnc_sp, 0, {K_Z}, {"z"}, {0},
     {K_ONE, K_D}, {"log_f", "dlog_f"}, {0, 1}},
    {"bingham_log_normalization_hessian", c_hess, 0, {K_Z}, {"z"}, {0}, {K_ONE, K_D, K_DD},
     {"log_f", "dlog_f", "d2log_f"}, {0, 1, 0}},
    {"bingham_second_moment", c_sm, 0, {K_M, K_Z}, {"m", "z"}, {0, 0}, {K_DD}, {"s"}, {0}},
    {"bingham_mle", c_mle, 0, {K_S}, {"s"}, {0}, {K_DD, K_D}, {"m", "z"}, {0, 0}},
    {"bingham_mle_samples", c_mles, 0, {K_X, K_W}, {"x", "w"}, {0, 1}, {K_DD, K_D}, {"m", "z"},
     {0, 0}},
    {"bingham_multiply", c_mul, 0, {K_M, K_Z, K_M, K_Z}, {"m1", "z1", "m2", "z2"}, {0, 0, 0, 0},
     {K_DD, K_D}, {"m", "z"}, {0, 0}},
    {"bingham_compose", c_comp, 1, {K_M, K_Z, K_M, K_Z}, {"m1", "z1", "m2", "z2"}, {0, 0, 0, 0},
     {K_DD, K_D}, {"m", "z"}, {0, 0}},
    {"bingham_pdf", c_pdf, 0, {K_M, K_Z, K_X}, {"m", "z", "x"}, {0, 0, 0}, {K_N}, {"p"}, {0}},
    {"bingham_log_pdf", c_lpdf, 0, {K_M, K_Z, K_X}, {"m", "z", "x"}, {0, 0, 0}, {K_N}, {"log_p"},
     {0}},
    {"bingham_entropy", c_ent, 0, {K_M, K_Z}, {"m", "z"}, {0, 0}, {K_ONE}, {"h"}, {0}},
    {"bingham_kl_divergence", c_kl, 0, {K_M, K_Z, K_M, K_Z}, {"m1", "z1", "m2", "z2"},
     {0, 0, 0, 0}, {K_ONE}, {"kl"}, {0}},
    {"bingham_sample", c_samp, 0, {K_M, K_Z}, {"m", "z"}, {0, 0}, {K_ND}, {"x_out"}, {0}},
    {"bingham_rotate_left", c_rotl, 1, {K_M, K_Z, K_U}, {"m", "z", "u"}, {0, 0, 0}, {K_DD, K_D},
     {"m_out", "z_out"}, {0, 0}},
    {"bingham_rotate_right", c_rotr, 1, {K_M, K_Z, K_U}, {"m", "z", "u"}, {0, 0, 0}, {K_DD, K_D},
     {"m_out", "z_out"}, {0, 0}},
    {"bingham_mode", c_mode, 0, {K_M, K_Z}, {"m", "z"}, {0, 0}, {K_D}, {"mode"}, {0}},
};
#define N_FUNCTIONS (sizeof FUNCTIONS / sizeof FUNCTIONS[0])

/* ---- test data --------------------------------------------------------------------------- */

static size_t kind_len(int kind, size_t d, size_t n) {
    switch (kind) {
    case K_M: case K_S: case K_DD: return d * d;
    case K_Z: case K_U: case K_D: return d;
    case K_X: case K_ND: return n * d;
    case K_W: case K_N: return n;
    case K_ONE: return 1;
    default: return 0;
    }
}

/* Valid content for an input of the given kind. `which` varies the data between arguments. */
static void fill_input(int kind, size_t d, size_t n, double *a, int which) {
    switch (kind) {
    case K_M: fill_orthogonal(d, a, 0.4 * which); break;
    case K_Z: /* unsorted, shifted, distinct */
        for (size_t i = 0; i < d; ++i) a[i] = 1.5 - (double)((i * 5 + (size_t)which) % d) * (0.7 + 0.1 * which);
        break;
    case K_S: { /* M diag(omega) M^T with omega_i proportional to i + 1 */
        double m[64 * 64];
        fill_orthogonal(d, m, 0.1);
        double tot = (double)(d * (d + 1)) / 2.0;
        for (size_t r = 0; r < d; ++r)
            for (size_t c = 0; c < d; ++c) {
                double s = 0;
                for (size_t k = 0; k < d; ++k) s += m[r * d + k] * ((double)(k + 1) / tot) * m[c * d + k];
                a[r * d + c] = s;
            }
        for (size_t r = 0; r < d; ++r) /* exact symmetry */
            for (size_t c = 0; c < r; ++c) a[r * d + c] = a[c * d + r];
        break;
    }
    case K_X:
        for (size_t k = 0; k < n; ++k) {
            for (size_t i = 0; i < d; ++i) a[k * d + i] = sin(1.3 * (double)i + 2.1 * (double)k + 0.7 * (double)(i * k) + 0.4);
            normalize(a + k * d, d);
        }
        break;
    case K_W:
        for (size_t k = 0; k < n; ++k) a[k] = 0.5 + (double)k;
        break;
    case K_U:
        for (size_t i = 0; i < d; ++i) a[i] = 0.3 + 0.2 * (double)i;
        normalize(a, d);
        break;
    default: break;
    }
}

typedef struct {
    double *in[4];
    double *out[3];
    size_t in_len[4], out_len[3];
} buffers_t;

static void buffers_alloc(const fn_t *f, size_t d, size_t n, buffers_t *b) {
    memset(b, 0, sizeof *b);
    for (int i = 0; i < 4; ++i) {
        b->in_len[i] = kind_len(f->in_kind[i], d, n);
        if (f->in_kind[i] != K_NONE) {
            b->in[i] = (double *)calloc(b->in_len[i] + 1, sizeof(double));
            fill_input(f->in_kind[i], d, n, b->in[i], i / 2);
        }
    }
    for (int i = 0; i < 3; ++i) {
        b->out_len[i] = kind_len(f->out_kind[i], d, n);
        if (f->out_kind[i] != K_NONE) b->out[i] = (double *)calloc(b->out_len[i] + 1, sizeof(double));
    }
}

static void buffers_free(buffers_t *b) {
    for (int i = 0; i < 4; ++i) free(b->in[i]);
    for (int i = 0; i < 3; ++i) free(b->out[i]);
}

static void sentinel(buffers_t *b) {
    for (int i = 0; i < 3; ++i)
        if (b->out[i]) memset(b->out[i], 0xA5, (b->out_len[i] + 1) * sizeof(double));
}

static int outputs_untouched(const buffers_t *b) {
    for (int i = 0; i < 3; ++i) {
        if (!b->out[i]) continue;
        const unsigned char *p = (const unsigned char *)b->out[i];
        for (size_t k = 0; k < (b->out_len[i] + 1) * sizeof(double); ++k)
            if (p[k] != 0xA5) return 0;
    }
    return 1;
}

static void make_call(size_t d, size_t n, const buffers_t *b, call_t *c) {
    memset(c, 0, sizeof *c);
    c->d = d;
    c->n = n;
    c->seed = 42;
    for (int i = 0; i < 4; ++i) c->in[i] = b->in[i];
    for (int i = 0; i < 3; ++i) c->out[i] = b->out[i];
}

/* After a failure: the message starts with the function's name and contains `needle`. */
#define check_message(f, needle) CHECK_MESSAGE((f)->name, needle)

static int all_finite(const buffers_t *b) {
    for (int i = 0; i < 3; ++i) {
        if (!b->out[i]) continue;
        for (size_t k = 0; k < b->out_len[i]; ++k)
            if (!isfinite(b->out[i][k])) return 0;
    }
    return 1;
}

/* ---- the table-driven tests ---------------------------------------------------------------- */

static void test_function(const fn_t *f) {
    const size_t dims[] = {2, 3, 4, 7};
    char needle[64];
    for (size_t di = 0; di < sizeof dims / sizeof dims[0]; ++di) {
        size_t d = dims[di];
        int supported = !f->only_2_4 || d == 2 || d == 4;
        buffers_t b;
        call_t c;
        buffers_alloc(f, d, NS, &b);
        make_call(d, NS, &b, &c);
        sentinel(&b);
        if (!supported) {
            CHECK_STATUS(f->call(&c), BINGHAM_ERR_INVALID_DIMENSION);
            CHECK(outputs_untouched(&b));
            check_message(f, "d");
            buffers_free(&b);
            continue;
        }
        /* success path */
        CHECK_OK(f->call(&c));
        CHECK(all_finite(&b));
        /* keep the successful result to compare with calls leaving out optional outputs */
        double *ref[3] = {0, 0, 0};
        for (int i = 0; i < 3; ++i)
            if (b.out[i]) {
                ref[i] = (double *)malloc(b.out_len[i] * sizeof(double));
                memcpy(ref[i], b.out[i], b.out_len[i] * sizeof(double));
            }
        /* NULL inputs */
        for (int i = 0; i < 4; ++i) {
            if (f->in_kind[i] == K_NONE) continue;
            make_call(d, NS, &b, &c);
            c.in[i] = NULL;
            sentinel(&b);
            if (f->in_optional[i]) {
                CHECK_OK(f->call(&c));
            } else {
                CHECK_STATUS(f->call(&c), BINGHAM_ERR_NULL_ARGUMENT);
                CHECK(outputs_untouched(&b));
                snprintf(needle, sizeof needle, "`%s` is NULL", f->in_name[i]);
                check_message(f, needle);
            }
        }
        /* NULL outputs */
        for (int i = 0; i < 3; ++i) {
            if (f->out_kind[i] == K_NONE) continue;
            make_call(d, NS, &b, &c);
            c.out[i] = NULL;
            sentinel(&b);
            if (f->out_optional[i]) {
                CHECK_OK(f->call(&c));
                for (int k = 0; k < 3; ++k)
                    if (k != i && b.out[k])
                        CHECK(memcmp(b.out[k], ref[k], b.out_len[k] * sizeof(double)) == 0);
            } else {
                CHECK_STATUS(f->call(&c), BINGHAM_ERR_NULL_ARGUMENT);
                CHECK(outputs_untouched(&b));
                snprintf(needle, sizeof needle, "`%s` is NULL", f->out_name[i]);
                check_message(f, needle);
            }
        }
        /* NaN / Inf in every input, at the first and the last position */
        const double bad[3] = {NAN, INFINITY, -INFINITY};
        for (int i = 0; i < 4; ++i) {
            if (f->in_kind[i] == K_NONE) continue;
            size_t len = b.in_len[i];
            size_t pos[2] = {0, len - 1};
            for (int p = 0; p < 2; ++p)
                for (int v = 0; v < 3; ++v) {
                    double saved = b.in[i][pos[p]];
                    b.in[i][pos[p]] = bad[v];
                    make_call(d, NS, &b, &c);
                    sentinel(&b);
                    CHECK_STATUS(f->call(&c), BINGHAM_ERR_INVALID_ARGUMENT);
                    CHECK(outputs_untouched(&b));
                    snprintf(needle, sizeof needle, "`%s[%zu]` = ", f->in_name[i], pos[p]);
                    check_message(f, needle);
                    b.in[i][pos[p]] = saved;
                }
        }
        /* M not orthogonal: just outside and just inside the tolerance */
        for (int i = 0; i < 4; ++i) {
            if (f->in_kind[i] != K_M) continue;
            for (int inside = 0; inside < 2; ++inside) {
                double *m = b.in[i];
                double saved = m[0];
                m[0] += inside ? 1e-8 : 1e-4;
                make_call(d, NS, &b, &c);
                sentinel(&b);
                if (inside) {
                    CHECK_OK(f->call(&c));
                } else {
                    CHECK_STATUS(f->call(&c), BINGHAM_ERR_INVALID_ARGUMENT);
                    CHECK(outputs_untouched(&b));
                    check_message(f, "orthogonal");
                }
                m[0] = saved;
            }
        }
        /* vectors that must be unit length: scaled just outside / inside the tolerance */
        for (int i = 0; i < 4; ++i) {
            if (f->in_kind[i] != K_X && f->in_kind[i] != K_U) continue;
            size_t row = f->in_kind[i] == K_X ? NS - 1 : 0; /* the last point */
            for (int inside = 0; inside < 2; ++inside) {
                double *v = b.in[i] + row * d;
                double scale = inside ? 1.0 + 5e-4 : 1.0 + 1e-2; /* BINGHAM_UNIT_TOL = 1e-3 */
                for (size_t k = 0; k < d; ++k) v[k] *= scale;
                make_call(d, NS, &b, &c);
                sentinel(&b);
                if (inside) {
                    CHECK_OK(f->call(&c));
                } else {
                    CHECK_STATUS(f->call(&c), BINGHAM_ERR_INVALID_ARGUMENT);
                    CHECK(outputs_untouched(&b));
                    check_message(f, "unit");
                    check_message(f, "normalize it first");
                    if (f->in_kind[i] == K_X && f->call != c_mles) {
                        snprintf(needle, sizeof needle, "x row %d", NS - 1);
                        check_message(f, needle);
                    }
                }
                for (size_t k = 0; k < d; ++k) v[k] /= scale;
            }
        }
        for (int i = 0; i < 3; ++i) free(ref[i]);
        buffers_free(&b);
    }

    /* invalid d: every pointer aims at an inaccessible page */
    const size_t bad_dims[] = {0, 1, 65, (size_t)-1};
    for (size_t k = 0; k < sizeof bad_dims / sizeof bad_dims[0]; ++k) {
        call_t c;
        memset(&c, 0, sizeof c);
        c.d = bad_dims[k];
        c.n = NS;
        for (int i = 0; i < 4; ++i) c.in[i] = f->in_kind[i] != K_NONE ? no_access() : NULL;
        for (int i = 0; i < 3; ++i) c.out[i] = f->out_kind[i] != K_NONE ? no_access() : NULL;
        CHECK_STATUS(f->call(&c), BINGHAM_ERR_INVALID_DIMENSION);
        check_message(f, "d = ");
        /* NULL everywhere with a bad d: still the dimension error, d is checked first */
        memset(c.in, 0, sizeof c.in);
        memset(c.out, 0, sizeof c.out);
        CHECK_STATUS(f->call(&c), BINGHAM_ERR_INVALID_DIMENSION);
    }
}

/* ---- special cases ----------------------------------------------------------------------- */

static void test_normalization_special(void) {
    double z[3] = {800.0, 0.0, -1.0}, f = -7, df[3] = {-7, -7, -7}, lf = 0, w[3];
    CHECK_STATUS(bingham_normalization_constant(3, z, &f, df), BINGHAM_ERR_NUMERICAL);
    CHECK(f == -7 && df[0] == -7 && df[1] == -7 && df[2] == -7);
    CHECK(strstr(check_last_message(), "bingham_log_normalization_constant") != NULL);
    CHECK_OK(bingham_log_normalization_constant(3, z, &lf, w));
    CHECK(isfinite(lf) && lf > 790.0);
    CHECK_CLOSE(w[0] + w[1] + w[2], 1.0, 1e-13);
    /* underflow: refused rather than returning 0 */
    double zu[2] = {-1e300, -1e300};
    CHECK_STATUS(bingham_normalization_constant(2, zu, &f, NULL), BINGHAM_ERR_NUMERICAL);
    CHECK(f == -7);
    /* F(0) = |S^{d-1}| */
    double z0[4] = {0, 0, 0, 0};
    CHECK_OK(bingham_normalization_constant(2, z0, &f, NULL));
    CHECK_CLOSE(f, 2 * M_PI, 1e-14);
    CHECK_OK(bingham_normalization_constant(3, z0, &f, NULL));
    CHECK_CLOSE(f, 4 * M_PI, 1e-14);
    CHECK_OK(bingham_normalization_constant(4, z0, &f, NULL));
    CHECK_CLOSE(f, 2 * M_PI * M_PI, 1e-14);
    /* shift: F(Z + cI) = e^c F(Z); order: gradient follows the input */
    double za[3] = {-3, 0, -1}, zb[3] = {-2, 1, 0}, fa, fb, ga[3], gb[3];
    CHECK_OK(bingham_normalization_constant(3, za, &fa, ga));
    CHECK_OK(bingham_normalization_constant(3, zb, &fb, gb));
    CHECK_CLOSE(fb, fa * exp(1.0), 1e-13);
    CHECK_CLOSE(gb[0], ga[0] * exp(1.0), 1e-13);
    CHECK_CLOSE(gb[1], ga[1] * exp(1.0), 1e-13);
    CHECK(ga[1] > ga[2] && ga[2] > ga[0]); /* E[x_i^2] grows with z_i */
    /* saddlepoint: close to exact, but explicitly not the same */
    double ls, le;
    CHECK_OK(bingham_log_normalization_constant_saddlepoint(3, za, &ls, NULL));
    CHECK_OK(bingham_log_normalization_constant(3, za, &le, NULL));
    CHECK(fabs(ls - le) < 0.05 && ls != le);
    /* Hessian: symmetric, rows sum to zero (sum of omega is 1) */
    double h[9], g[3], l;
    CHECK_OK(bingham_log_normalization_hessian(3, za, &l, g, h));
    CHECK_CLOSE(l, le, 1e-14);
    for (int i = 0; i < 3; ++i) {
        CHECK_CLOSE(h[i * 3] + h[i * 3 + 1] + h[i * 3 + 2], 0.0, 1e-12);
        for (int j = 0; j < 3; ++j) CHECK_CLOSE(h[i * 3 + j], h[j * 3 + i], 1e-14);
    }
}

static void test_mle_special(void) {
    double m[9], z[3];
    memset(m, 0xA5, sizeof m);
    memset(z, 0xA5, sizeof z);
    unsigned char sm[sizeof m], sz[sizeof z];
    memcpy(sm, m, sizeof m);
    memcpy(sz, z, sizeof z);
    const double not_symmetric[9] = {0.5, 0.1, 0, 0, 0.3, 0, 0, 0, 0.2};
    const double negative[9] = {1.2, 0, 0, 0, -0.1, 0, 0, 0, -0.1};
    const double zero[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    CHECK_STATUS(bingham_mle(3, not_symmetric, m, z), BINGHAM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(check_last_message(), "symmetric") != NULL);
    CHECK_STATUS(bingham_mle(3, negative, m, z), BINGHAM_ERR_INVALID_ARGUMENT);
    CHECK_STATUS(bingham_mle(3, zero, m, z), BINGHAM_ERR_INVALID_ARGUMENT);
    CHECK(memcmp(m, sm, sizeof m) == 0 && memcmp(z, sz, sizeof z) == 0);
    /* uniform second moment -> z = 0 */
    const double uniform[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    CHECK_OK(bingham_mle(3, uniform, m, z));
    CHECK(fabs(z[0]) < 1e-8 && fabs(z[1]) < 1e-8 && z[2] == 0.0);
    memcpy(sm, m, sizeof m);
    memcpy(sz, z, sizeof z);
    /* samples: n = 0, negative and all-zero weights */
    const double x[6] = {1, 0, 0, 0, 1, 0};
    const double wneg[2] = {1, -1}, wzero[2] = {0, 0};
    CHECK_STATUS(bingham_mle_samples(3, 0, x, NULL, m, z), BINGHAM_ERR_INVALID_ARGUMENT);
    CHECK_STATUS(bingham_mle_samples(3, 0, NULL, NULL, m, z), BINGHAM_ERR_INVALID_ARGUMENT);
    CHECK_STATUS(bingham_mle_samples(3, 2, x, wneg, m, z), BINGHAM_ERR_INVALID_ARGUMENT);
    CHECK_STATUS(bingham_mle_samples(3, 2, x, wzero, m, z), BINGHAM_ERR_INVALID_ARGUMENT);
    CHECK_STATUS(bingham_mle_samples(3, (size_t)-1 / 2, x, NULL, m, z), BINGHAM_ERR_INVALID_DIMENSION);
    CHECK(memcmp(m, sm, sizeof m) == 0 && memcmp(z, sz, sizeof z) == 0);
}

static void test_counts_and_aliasing(void) {
    double m[16], z[4] = {-5, -1, -2, 0}, p[1] = {-7}, xs[8];
    fill_orthogonal(4, m, 0.0);
    /* n = 0: nothing to do, NULL allowed */
    CHECK_OK(bingham_pdf(4, m, z, 0, NULL, NULL));
    CHECK_OK(bingham_log_pdf(4, m, z, 0, NULL, NULL));
    CHECK_OK(bingham_sample(4, m, z, 1, 0, NULL));
    CHECK_STATUS(bingham_pdf(4, m, z, (size_t)-1 / 2, xs, p), BINGHAM_ERR_INVALID_DIMENSION);
    CHECK_STATUS(bingham_sample(4, m, z, 1, (size_t)-1 / 2, xs), BINGHAM_ERR_INVALID_DIMENSION);
    CHECK(p[0] == -7);
    /* sampling is deterministic in the seed, and samples are unit vectors */
    double a[40], b[40], c[40];
    CHECK_OK(bingham_sample(4, m, z, 123, 10, a));
    CHECK_OK(bingham_sample(4, m, z, 123, 10, b));
    CHECK_OK(bingham_sample(4, m, z, 124, 10, c));
    CHECK(memcmp(a, b, sizeof a) == 0);
    CHECK(memcmp(a, c, sizeof a) != 0);
    for (int k = 0; k < 10; ++k) {
        double s = 0;
        for (int i = 0; i < 4; ++i) s += a[k * 4 + i] * a[k * 4 + i];
        CHECK_CLOSE(s, 1.0, 1e-12);
    }
    /* in place: outputs may alias inputs */
    double m1[16], z1[4] = {-3, 0, -1, -2}, m2[16], z2[4] = {-1, -4, 0, -2}, mr[16], zr[4];
    fill_orthogonal(4, m1, 0.0);
    fill_orthogonal(4, m2, 0.5);
    CHECK_OK(bingham_multiply(4, m1, z1, m2, z2, mr, zr));
    CHECK_OK(bingham_multiply(4, m1, z1, m2, z2, m1, z1));
    CHECK(memcmp(m1, mr, sizeof mr) == 0 && memcmp(z1, zr, sizeof zr) == 0);
    /* outputs are normalized: z ascending, last 0, M orthogonal */
    CHECK(zr[0] <= zr[1] && zr[1] <= zr[2] && zr[3] == 0.0);
    double md[4];
    CHECK_OK(bingham_mode(4, mr, zr, md));
    for (int i = 0; i < 4; ++i) CHECK(md[i] == mr[i * 4 + 3]);
}

/* ---- deterministic samples and the nonlinear filter steps ------------------------------------ */

static size_t expected_count(size_t d, int scheme) {
    return scheme == BINGHAM_SAMPLES_TAC2016 ? 2 * d - 1 : 2 * d * d - 4 * d + 3;
}

static void test_deterministic_sample_count(void) {
    size_t n = 12345;
    for (size_t d = 2; d <= 64; d += (d < 8 ? 1 : 28)) {
        CHECK_OK(bingham_deterministic_sample_count(d, BINGHAM_SAMPLES_TAC2016, &n));
        CHECK(n == expected_count(d, BINGHAM_SAMPLES_TAC2016));
        CHECK_OK(bingham_deterministic_sample_count(d, BINGHAM_SAMPLES_MOMENTS, &n));
        CHECK(n == expected_count(d, BINGHAM_SAMPLES_MOMENTS));
    }
    CHECK(n == 2 * 64 * 64 - 4 * 64 + 3);
    n = 12345;
    const size_t bad_dims[] = {0, 1, 65, (size_t)-1};
    for (size_t k = 0; k < sizeof bad_dims / sizeof bad_dims[0]; ++k) {
        CHECK_STATUS(bingham_deterministic_sample_count(bad_dims[k], BINGHAM_SAMPLES_MOMENTS, &n),
                     BINGHAM_ERR_INVALID_DIMENSION);
        CHECK_MESSAGE("bingham_deterministic_sample_count", "d = ");
        CHECK_STATUS(bingham_deterministic_sample_count(bad_dims[k], 0, (size_t *)no_access()),
                     BINGHAM_ERR_INVALID_DIMENSION);
    }
    const int bad_schemes[] = {-1, 2, 1 << 30};
    for (int k = 0; k < 3; ++k) {
        CHECK_STATUS(bingham_deterministic_sample_count(3, bad_schemes[k], &n), BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK_MESSAGE("bingham_deterministic_sample_count", "scheme");
    }
    CHECK_STATUS(bingham_deterministic_sample_count(3, 0, NULL), BINGHAM_ERR_NULL_ARGUMENT);
    CHECK_MESSAGE("bingham_deterministic_sample_count", "`count` is NULL");
    CHECK(n == 12345);
}

#define DS_CAP 20 /* >= 19, the MOMENTS count for d = 4 */

typedef struct {
    double points[(DS_CAP + 1) * 4], weights[DS_CAP + 1];
    size_t count;
    int reproduced;
} ds_out_t;

static void ds_sentinel(ds_out_t *o) { memset(o, 0xA5, sizeof *o); }

static int ds_untouched(const ds_out_t *o) {
    const unsigned char *p = (const unsigned char *)o;
    for (size_t k = 0; k < sizeof *o; ++k)
        if (p[k] != 0xA5) return 0;
    return 1;
}

static void test_deterministic_samples(void) {
    const size_t dims[] = {2, 3, 4};
    const int schemes[] = {BINGHAM_SAMPLES_TAC2016, BINGHAM_SAMPLES_MOMENTS};
    char needle[96];
    for (size_t di = 0; di < 3; ++di)
        for (int si = 0; si < 2; ++si) {
            size_t d = dims[di];
            int scheme = schemes[si];
            size_t need = expected_count(d, scheme);
            double m[16], z[4];
            ds_out_t o, ref;
            fill_orthogonal(d, m, 0.2);
            fill_input(K_Z, d, 0, z, 0);
            /* success with exactly the needed capacity: rows beyond *count untouched */
            ds_sentinel(&o);
            CHECK_OK(bingham_deterministic_samples(d, m, z, scheme, 0.5, need, o.points, o.weights, &o.count,
                                                   &o.reproduced));
            CHECK(o.count <= need && (o.reproduced == 2 || o.reproduced == 4));
            if (scheme == BINGHAM_SAMPLES_TAC2016) CHECK(o.count == need && o.reproduced == 2);
            double sum = 0;
            for (size_t k = 0; k < o.count; ++k) {
                double s = 0;
                for (size_t i = 0; i < d; ++i) s += o.points[k * d + i] * o.points[k * d + i];
                CHECK_CLOSE(s, 1.0, 1e-14);
                CHECK(o.weights[k] >= 0);
                sum += o.weights[k];
            }
            CHECK_CLOSE(sum, 1.0, 1e-14);
            {
                const unsigned char *p = (const unsigned char *)(o.points + o.count * d);
                int clean = 1;
                for (size_t k = 0; k < (DS_CAP + 1 - o.count) * d * sizeof(double); ++k) clean &= p[k] == 0xA5;
                CHECK(clean);
            }
            ref = o;
            /* reproduced may be NULL; a larger capacity is fine; lambda is ignored by MOMENTS */
            ds_sentinel(&o);
            CHECK_OK(bingham_deterministic_samples(d, m, z, scheme, scheme == BINGHAM_SAMPLES_MOMENTS ? NAN : 0.5,
                                                   DS_CAP, o.points, o.weights, &o.count, NULL));
            CHECK(o.count == ref.count && memcmp(o.points, ref.points, o.count * d * sizeof(double)) == 0 &&
                  memcmp(o.weights, ref.weights, o.count * sizeof(double)) == 0);
            /* NULL pointers */
            const char *names[] = {"m", "z", "points", "weights", "count"};
            for (int k = 0; k < 5; ++k) {
                ds_sentinel(&o);
                bingham_status st = bingham_deterministic_samples(
                    d, k == 0 ? NULL : m, k == 1 ? NULL : z, scheme, 0.5, need, k == 2 ? NULL : o.points,
                    k == 3 ? NULL : o.weights, k == 4 ? NULL : &o.count, &o.reproduced);
                CHECK_STATUS(st, BINGHAM_ERR_NULL_ARGUMENT);
                CHECK(ds_untouched(&o));
                snprintf(needle, sizeof needle, "`%s` is NULL", names[k]);
                CHECK_MESSAGE("bingham_deterministic_samples", needle);
            }
            /* capacity one short: the message gives the needed count */
            ds_sentinel(&o);
            CHECK_STATUS(bingham_deterministic_samples(d, m, z, scheme, 0.5, need - 1, o.points, o.weights, &o.count,
                                                       &o.reproduced),
                         BINGHAM_ERR_INVALID_DIMENSION);
            CHECK(ds_untouched(&o));
            snprintf(needle, sizeof needle, "the %zu points", need);
            CHECK_MESSAGE("bingham_deterministic_samples", needle);
            /* NaN / Inf in m and z */
            for (int k = 0; k < 2; ++k) {
                double *a = k == 0 ? m : z;
                size_t pos = k == 0 ? d * d - 1 : 0;
                double saved = a[pos];
                a[pos] = k == 0 ? NAN : -INFINITY;
                ds_sentinel(&o);
                CHECK_STATUS(bingham_deterministic_samples(d, m, z, scheme, 0.5, need, o.points, o.weights, &o.count,
                                                           &o.reproduced),
                             BINGHAM_ERR_INVALID_ARGUMENT);
                CHECK(ds_untouched(&o));
                snprintf(needle, sizeof needle, "`%s[%zu]` = ", k == 0 ? "m" : "z", pos);
                CHECK_MESSAGE("bingham_deterministic_samples", needle);
                a[pos] = saved;
            }
            /* m not orthogonal */
            m[0] += 1e-4;
            ds_sentinel(&o);
            CHECK_STATUS(bingham_deterministic_samples(d, m, z, scheme, 0.5, need, o.points, o.weights, &o.count,
                                                       &o.reproduced),
                         BINGHAM_ERR_INVALID_ARGUMENT);
            CHECK(ds_untouched(&o));
            CHECK_MESSAGE("bingham_deterministic_samples", "orthogonal");
            m[0] -= 1e-4;
            /* lambda outside [0, 1] (TAC 2016 only) and unknown schemes */
            if (scheme == BINGHAM_SAMPLES_TAC2016) {
                const double bad_lambda[] = {-0.01, 1.01, NAN, INFINITY};
                for (int k = 0; k < 4; ++k) {
                    ds_sentinel(&o);
                    CHECK_STATUS(bingham_deterministic_samples(d, m, z, scheme, bad_lambda[k], need, o.points,
                                                               o.weights, &o.count, &o.reproduced),
                                 BINGHAM_ERR_INVALID_ARGUMENT);
                    CHECK(ds_untouched(&o));
                    CHECK_MESSAGE("bingham_deterministic_samples", "lambda");
                }
                const double ok_lambda[] = {0.0, 1.0};
                for (int k = 0; k < 2; ++k)
                    CHECK_OK(bingham_deterministic_samples(d, m, z, scheme, ok_lambda[k], need, o.points, o.weights,
                                                           &o.count, &o.reproduced));
            }
            ds_sentinel(&o);
            CHECK_STATUS(bingham_deterministic_samples(d, m, z, 2, 0.5, DS_CAP, o.points, o.weights, &o.count,
                                                       &o.reproduced),
                         BINGHAM_ERR_INVALID_ARGUMENT);
            CHECK(ds_untouched(&o));
            CHECK_MESSAGE("bingham_deterministic_samples", "unknown scheme 2");
        }
    /* invalid d: every pointer aims at an inaccessible page */
    const size_t bad_dims[] = {0, 1, 65, (size_t)-1};
    for (size_t k = 0; k < sizeof bad_dims / sizeof bad_dims[0]; ++k) {
        double *p = no_access();
        CHECK_STATUS(bingham_deterministic_samples(bad_dims[k], p, p, BINGHAM_SAMPLES_MOMENTS, 0.5, 1000, p, p,
                                                   (size_t *)no_access(), (int *)no_access()),
                     BINGHAM_ERR_INVALID_DIMENSION);
        CHECK_MESSAGE("bingham_deterministic_samples", "d = ");
        CHECK_STATUS(bingham_deterministic_samples(bad_dims[k], NULL, NULL, 0, 0.5, 0, NULL, NULL, NULL, NULL),
                     BINGHAM_ERR_INVALID_DIMENSION);
    }
}

/* Callbacks for the nonlinear filter steps; user_data points to a cb_ctx_t. */
typedef struct {
    size_t d;
    int calls;
    int rc; /* returned by the failing callbacks */
} cb_ctx_t;

/* The context of a callback, with the call counted. */
static cb_ctx_t *count_call(void *user_data) {
    cb_ctx_t *c = (cb_ctx_t *)user_data;
    ++c->calls;
    return c;
}

static int identity_transition(const double *x_in, double *x_out, void *user_data) {
    cb_ctx_t *c = count_call(user_data);
    memcpy(x_out, x_in, c->d * sizeof *x_out);
    return 0;
}

static int failing_transition(const double *x_in, double *x_out, void *user_data) {
    (void)x_in;
    (void)x_out;
    return count_call(user_data)->rc;
}

static int constant_log_likelihood(const double *x, double *log_l, void *user_data) {
    (void)x;
    count_call(user_data);
    *log_l = -2.5;
    return 0;
}

static int failing_log_likelihood(const double *x, double *log_l, void *user_data) {
    (void)x;
    (void)log_l;
    return count_call(user_data)->rc;
}

/* The _opts forms: defaults, bad options refused before any callback, the report, the budget. */
static void test_nonlinear_options(bingham_filter *f, size_t d, const double *mw, const double *zw) {
    double sm[16], sz[4], am[16], az[4];
    bingham_nonlinear_options o;
    bingham_nonlinear_report r;
    cb_ctx_t c = {d, 0, 0};
    CHECK_STATUS(bingham_nonlinear_options_default(NULL), BINGHAM_ERR_NULL_ARGUMENT);
    CHECK_MESSAGE("bingham_nonlinear_options_default", "`opts` is NULL");
    CHECK_OK(bingham_nonlinear_options_default(&o));
    CHECK(o.tolerance == 0 && o.mode_tolerance == 0.05 && o.max_calls == 20000);
    CHECK(BINGHAM_NONLINEAR_PREDICT_TOLERANCE == 5e-4 && BINGHAM_NONLINEAR_UPDATE_TOLERANCE == 2.5e-3);
    CHECK_OK(bingham_filter_get_state(f, sm, sz));
    /* options out of range: refused before the callback, nothing written */
    const double bad_tol[] = {-1e-3, NAN, INFINITY};
    for (int k = 0; k < 3; ++k) {
        bingham_nonlinear_options b = o;
        b.tolerance = bad_tol[k];
        memset(&r, 0x5a, sizeof r);
        bingham_nonlinear_report before = r;
        CHECK_STATUS(bingham_filter_update_nonlinear_opts(f, constant_log_likelihood, &c, &b, &r), BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK_MESSAGE("bingham_filter_update_nonlinear_opts", "tolerance");
        CHECK_STATUS(bingham_filter_predict_nonlinear_opts(f, identity_transition, &c, mw, zw, &b, &r), BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK_MESSAGE("bingham_filter_predict_nonlinear_opts", "tolerance");
        CHECK(memcmp(&r, &before, sizeof r) == 0);
        b = o;
        b.mode_tolerance = k == 0 ? 0.0 : bad_tol[k];
        CHECK_STATUS(bingham_filter_update_nonlinear_opts(f, constant_log_likelihood, &c, &b, &r), BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK_MESSAGE("bingham_filter_update_nonlinear_opts", "mode_tolerance");
    }
    bingham_nonlinear_options b = o;
    b.max_calls = 0;
    CHECK_STATUS(bingham_filter_update_nonlinear_opts(f, constant_log_likelihood, &c, &b, NULL), BINGHAM_ERR_INVALID_ARGUMENT);
    CHECK_MESSAGE("bingham_filter_update_nonlinear_opts", "max_calls");
    CHECK(c.calls == 0);
    /* a budget too small: refused with the estimate, the state unchanged */
    b.max_calls = 40;
    CHECK_STATUS(bingham_filter_update_nonlinear_opts(f, constant_log_likelihood, &c, &b, &r), BINGHAM_ERR_NOT_CONVERGED);
    CHECK_MESSAGE("bingham_filter_update_nonlinear_opts", "budget (40 calls");
    CHECK(c.calls <= 40);
    CHECK_OK(bingham_filter_get_state(f, am, az));
    CHECK(memcmp(am, sm, d * d * sizeof(double)) == 0 && memcmp(az, sz, d * sizeof(double)) == 0);
    /* success: the report counts the calls; NULL options and report are the defaults / unwanted */
    c.calls = 0;
    CHECK_OK(bingham_filter_update_nonlinear_opts(f, constant_log_likelihood, &c, NULL, &r));
    CHECK(r.calls == (size_t)c.calls && r.method == BINGHAM_NONLINEAR_SAMPLED && r.samples >= 128);
    CHECK(r.error_estimate <= BINGHAM_NONLINEAR_UPDATE_TOLERANCE && r.mode_error_estimate <= 0.05);
    CHECK(r.effective_share > 0 && r.effective_share <= 1);
    CHECK_OK(bingham_filter_update_nonlinear_opts(f, constant_log_likelihood, &c, &o, NULL));
    /* the identity transition: the deterministic points alone, exact */
    c.calls = 0;
    CHECK_OK(bingham_filter_predict_nonlinear_opts(f, identity_transition, &c, mw, zw, &o, &r));
    CHECK(r.calls == (size_t)c.calls && r.method == BINGHAM_NONLINEAR_DETERMINISTIC && r.samples == 0);
    CHECK(r.error_estimate < 1e-12 && r.effective_share == 1);
}

static void test_nonlinear_filter(void) {
    const size_t dims[] = {2, 4};
    for (int di = 0; di < 2; ++di) {
        size_t d = dims[di];
        double m[16], z[4] = {-5, -1, -3, 0}, mw[16], zw[4] = {-40, -60, -50, 0};
        double sm[16], sz[4], am[16], az[4];
        fill_orthogonal(d, m, 0.3);
        fill_orthogonal(d, mw, 0.7);
        bingham_filter *f = NULL;
        CHECK_OK(bingham_filter_new(d, m, z, &f));
        CHECK_OK(bingham_filter_get_state(f, sm, sz));
        cb_ctx_t c = {d, 0, 0};
        /* NULL handle, callback, noise: refused before the callback is called */
        CHECK_STATUS(bingham_filter_predict_nonlinear(NULL, identity_transition, &c, mw, zw), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE("bingham_filter_predict_nonlinear", "`f` is NULL");
        CHECK_STATUS(bingham_filter_predict_nonlinear(f, NULL, &c, mw, zw), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE("bingham_filter_predict_nonlinear", "`fn` is NULL");
        CHECK_STATUS(bingham_filter_predict_nonlinear(f, identity_transition, &c, NULL, zw), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE("bingham_filter_predict_nonlinear", "`m_w` is NULL");
        CHECK_STATUS(bingham_filter_predict_nonlinear(f, identity_transition, &c, mw, NULL), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE("bingham_filter_predict_nonlinear", "`z_w` is NULL");
        /* invalid noise: refused before the callback is called */
        zw[1] = NAN;
        CHECK_STATUS(bingham_filter_predict_nonlinear(f, identity_transition, &c, mw, zw), BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK_MESSAGE("bingham_filter_predict_nonlinear", "`z_w[1]` = ");
        zw[1] = -60;
        mw[0] += 1e-4;
        CHECK_STATUS(bingham_filter_predict_nonlinear(f, identity_transition, &c, mw, zw), BINGHAM_ERR_INVALID_ARGUMENT);
        CHECK_MESSAGE("bingham_filter_predict_nonlinear", "orthogonal");
        mw[0] -= 1e-4;
        CHECK(c.calls == 0);
        CHECK_STATUS(bingham_filter_update_nonlinear(NULL, constant_log_likelihood, &c), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE("bingham_filter_update_nonlinear", "`f` is NULL");
        CHECK_STATUS(bingham_filter_update_nonlinear(f, NULL, &c), BINGHAM_ERR_NULL_ARGUMENT);
        CHECK_MESSAGE("bingham_filter_update_nonlinear", "`fn` is NULL");
        CHECK(c.calls == 0);
        /* failing callbacks: the return code is reported, the state unchanged */
        const int codes[] = {1, -1, 42};
        for (int k = 0; k < 3; ++k) {
            char needle[64];
            c.calls = 0;
            c.rc = codes[k];
            snprintf(needle, sizeof needle, "callback returned %d", codes[k]);
            CHECK_STATUS(bingham_filter_predict_nonlinear(f, failing_transition, &c, mw, zw), BINGHAM_ERR_CALLBACK);
            CHECK_MESSAGE("bingham_filter_predict_nonlinear", needle);
            CHECK_STATUS(bingham_filter_update_nonlinear(f, failing_log_likelihood, &c), BINGHAM_ERR_CALLBACK);
            CHECK_MESSAGE("bingham_filter_update_nonlinear", needle);
            CHECK(c.calls == 2); /* the first failing call ends the step */
        }
        CHECK_OK(bingham_filter_get_state(f, am, az));
        CHECK(memcmp(am, sm, d * d * sizeof(double)) == 0 && memcmp(az, sz, d * sizeof(double)) == 0);
        /* success: one call per deterministic sample; a constant likelihood changes nothing */
        c.calls = 0;
        CHECK_OK(bingham_filter_predict_nonlinear(f, identity_transition, &c, mw, zw));
        CHECK(c.calls == (int)expected_count(d, BINGHAM_SAMPLES_MOMENTS));
        CHECK_OK(bingham_filter_get_state(f, sm, sz));
        c.calls = 0;
        CHECK_OK(bingham_filter_update_nonlinear(f, constant_log_likelihood, &c));
        CHECK(c.calls > 0);
        CHECK_OK(bingham_filter_get_state(f, am, az));
        for (size_t i = 0; i < d; ++i) CHECK_CLOSE(az[i], sz[i], 1e-9);
        test_nonlinear_options(f, d, mw, zw);
        bingham_filter_free(f);
    }
}

/* ---- last error message, status strings, version -------------------------------------- */

static void test_last_error_message(void) {
    double f;
    CHECK_STATUS(bingham_normalization_constant(1, NULL, &f, NULL), BINGHAM_ERR_INVALID_DIMENSION);
    size_t full = 0;
    CHECK_OK(bingham_last_error_message(NULL, 0, &full));
    CHECK(full > 10);
    char buf[512];
    size_t len = 0;
    CHECK_OK(bingham_last_error_message(buf, sizeof buf, &len));
    CHECK(len == full && strlen(buf) == full);
    CHECK(strncmp(buf, "bingham_normalization_constant: ", 32) == 0);
    CHECK(strstr(buf, "d = 1") != NULL);
    /* truncation: at most len-1 bytes and a NUL; out_len still the full length */
    char small[8];
    memset(small, 'X', sizeof small);
    CHECK_OK(bingham_last_error_message(small, 5, &len));
    CHECK(len == full && strlen(small) == 4 && strncmp(small, buf, 4) == 0 && small[5] == 'X');
    memset(small, 'X', sizeof small);
    CHECK_OK(bingham_last_error_message(small, 1, &len));
    CHECK(small[0] == '\0' && small[1] == 'X' && len == full);
    /* len == 0 writes nothing, even with a buffer */
    memset(small, 'X', sizeof small);
    CHECK_OK(bingham_last_error_message(small, 0, &len));
    CHECK(small[0] == 'X');
    /* out_len may be NULL; buf NULL with len > 0 is refused */
    CHECK_OK(bingham_last_error_message(buf, sizeof buf, NULL));
    CHECK_STATUS(bingham_last_error_message(NULL, 4, &len), BINGHAM_ERR_NULL_ARGUMENT);
    /* reading (or failing to read) never changes the message; a successful call does not clear it */
    double z[2] = {-1, 0};
    CHECK_OK(bingham_normalization_constant(2, z, &f, NULL));
    CHECK_OK(bingham_last_error_message(small, sizeof small, &len));
    CHECK(len == full);
}

/* The first unread error is kept: an unchecked failure followed by another failure leaves a
 * message that names both (the newest first); a read (len > 0) resets this. */
static void test_first_unread_error(void) {
    char buf[1024];
    size_t len = 0;
    CHECK_OK(bingham_last_error_message(buf, sizeof buf, &len)); /* read: start clean */
    bingham_ahrs_params p;
    CHECK_OK(bingham_ahrs_params_default(0.01, &p));
    p.gyro_noise = -1.0;
    bingham_ahrs *a = NULL;
    /* the caller does not check this status ... */
    (void)bingham_ahrs_new(&p, &a);
    CHECK(a == NULL);
    /* ... and the next call fails because of it */
    double q[4];
    CHECK_STATUS(bingham_ahrs_quaternion(a, q), BINGHAM_ERR_NULL_ARGUMENT);
    size_t full = 0;
    CHECK_OK(bingham_last_error_message(NULL, 0, &full)); /* a length query is not a read */
    CHECK_OK(bingham_last_error_message(buf, sizeof buf, &len));
    CHECK(len == full && full < sizeof buf);
    CHECK(strncmp(buf, "bingham_ahrs_quaternion: ", 25) == 0);
    CHECK(strstr(buf, "[the first error since the message was last read: bingham_ahrs_new: ") != NULL);
    CHECK(strstr(buf, "gyro_noise") != NULL);
    /* after the read, the next failure stands alone */
    CHECK_STATUS(bingham_ahrs_quaternion(a, q), BINGHAM_ERR_NULL_ARGUMENT);
    CHECK_OK(bingham_last_error_message(buf, sizeof buf, &len));
    CHECK(strstr(buf, "first error") == NULL && strstr(buf, "gyro_noise") == NULL);
}

static void *thread_body(void *arg) {
    int which = *(int *)arg;
    double f;
    size_t d = which ? 70 : 0;
    for (int k = 0; k < 200; ++k) {
        bingham_normalization_constant(d, NULL, &f, NULL);
        char buf[256];
        size_t len;
        bingham_last_error_message(buf, sizeof buf, &len);
        if (!strstr(buf, which ? "d = 70" : "d = 0")) return (void *)1;
    }
    return NULL;
}

static void test_threads(void) {
    pthread_t t[2];
    int which[2] = {0, 1};
    void *r[2] = {(void *)1, (void *)1};
    for (int i = 0; i < 2; ++i) CHECK(pthread_create(&t[i], NULL, thread_body, &which[i]) == 0);
    for (int i = 0; i < 2; ++i) CHECK(pthread_join(t[i], &r[i]) == 0);
    CHECK(r[0] == NULL && r[1] == NULL);
}

static void test_status_strings_and_version(void) {
    CHECK(strcmp(bingham_status_str(BINGHAM_OK), "ok") == 0);
    CHECK(strcmp(bingham_status_str(BINGHAM_ERR_NULL_ARGUMENT), "null argument") == 0);
    CHECK(strcmp(bingham_status_str(BINGHAM_ERR_INVALID_DIMENSION), "invalid dimension") == 0);
    CHECK(strcmp(bingham_status_str(BINGHAM_ERR_INVALID_ARGUMENT), "invalid argument") == 0);
    CHECK(strcmp(bingham_status_str(BINGHAM_ERR_NOT_CONVERGED), "not converged") == 0);
    CHECK(strcmp(bingham_status_str(BINGHAM_ERR_NUMERICAL), "numerical failure") == 0);
    CHECK(strcmp(bingham_status_str(BINGHAM_ERR_PANIC), "internal error (panic)") == 0);
    CHECK(strcmp(bingham_status_str(BINGHAM_ERR_CALLBACK), "callback failed") == 0);
    CHECK(strcmp(bingham_status_str(8), "unknown status") == 0);
    CHECK(strcmp(bingham_status_str(-1), "unknown status") == 0);
    CHECK(strcmp(bingham_status_str(1 << 30), "unknown status") == 0);
    CHECK(BINGHAM_OK == 0 && BINGHAM_ERR_NULL_ARGUMENT == 1 && BINGHAM_ERR_INVALID_DIMENSION == 2 &&
          BINGHAM_ERR_INVALID_ARGUMENT == 3 && BINGHAM_ERR_NOT_CONVERGED == 4 &&
          BINGHAM_ERR_NUMERICAL == 5 && BINGHAM_ERR_PANIC == 6 && BINGHAM_ERR_CALLBACK == 7);
    char expect[64];
    snprintf(expect, sizeof expect, "%d.%d.%d", (int)BINGHAM_VERSION_MAJOR, (int)BINGHAM_VERSION_MINOR,
             (int)BINGHAM_VERSION_PATCH);
    CHECK(strcmp(bingham_version(), expect) == 0);
    CHECK(bingham_version() == bingham_version());
    CHECK(BINGHAM_MIN_DIM == 2 && BINGHAM_MAX_DIM == 64);
    CHECK(BINGHAM_ORTHOGONALITY_TOL == 1e-6 && BINGHAM_UNIT_TOL == 1e-3);
}

int main(void) {
    if (guard_pages_init()) return 1;
    {
        /* fresh thread state: no error yet -> empty message */
        size_t len = 99;
        char buf[4] = "abc";
        CHECK_OK(bingham_last_error_message(buf, sizeof buf, &len));
        CHECK(len == 0 && buf[0] == '\0');
    }
    for (size_t i = 0; i < N_FUNCTIONS; ++i) test_function(&FUNCTIONS[i]);
    test_normalization_special();
    test_mle_special();
    test_counts_and_aliasing();
    test_deterministic_sample_count();
    test_deterministic_samples();
    test_nonlinear_filter();
    test_last_error_message();
    test_first_unread_error();
    test_threads();
    test_status_strings_and_version();
    return check_summary("api_errors");
}
