/* Helpers shared by the C API tests (api_errors.c, ahrs_api.c, filter_api.c, spin_api.c,
 * world_api.c): input arrays placed flush against an inaccessible page, the filter handle's state
 * as raw bytes, test matrices and unit vectors, the expected message fragments, and the distance
 * between two Bingham exponents. Include after check.h, with _DEFAULT_SOURCE defined before any
 * #include (for MAP_ANONYMOUS under -std=c99); call guard_pages_init() first in main().
 * Everything here is static inline (no file-scope variables), so a program may use any part. */
#ifndef BINGHAM_C_TESTS_API_UTIL_H
#define BINGHAM_C_TESTS_API_UTIL_H

#ifndef _DEFAULT_SOURCE
#error "define _DEFAULT_SOURCE before any #include"
#endif

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

/* [readable page][PROT_NONE page], mapped by guard_pages_init(). */
typedef struct {
    unsigned char *base;
    size_t page_size;
} guard_pages_t;

static inline guard_pages_t *guard_pages(void) {
    static guard_pages_t g;
    return &g;
}

/* The start of the inaccessible page: any access crashes. */
static inline double *no_access(void) { return (double *)(guard_pages()->base + guard_pages()->page_size); }

/* A copy of src[0..n) ending exactly at an inaccessible page: reading past n crashes. There is
 * one such buffer: pass at most one flush() result per call. */
static inline double *flush(const double *src, size_t n) {
    double *p = no_access() - n;
    memcpy(p, src, n * sizeof(double));
    return p;
}

/* Maps the guard pages and makes the second one inaccessible; 0 on success, else 1 (with perror). */
static inline int guard_pages_init(void) {
    guard_pages_t *g = guard_pages();
    long ps = sysconf(_SC_PAGESIZE);
    g->page_size = ps > 0 ? (size_t)ps : 4096;
    g->base = mmap(NULL, 2 * g->page_size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (g->base == MAP_FAILED || mprotect(g->base + g->page_size, g->page_size, PROT_NONE)) {
        perror("mmap/mprotect");
        return 1;
    }
    return 0;
}

/* The state of a filter handle (d = 2 or 4; zero past d) as raw bytes, for bit-for-bit
 * comparisons. */
typedef struct {
    double m[16], z[4];
} snapshot;

/* Zeroes *s and reads the state of `f` into it; returns bingham_filter_get_state's status. */
static inline bingham_status snap_status(const bingham_filter *f, snapshot *s) {
    memset(s, 0, sizeof *s);
    return bingham_filter_get_state(f, s->m, s->z);
}

/* The state of `f`; exits the program if it cannot be read. */
static inline snapshot snap(const bingham_filter *f) {
    snapshot s;
    if (snap_status(f, &s) != BINGHAM_OK) {
        fprintf(stderr, "bingham_filter_get_state failed\n");
        exit(1);
    }
    return s;
}

static inline int same(snapshot a, snapshot b) { return memcmp(&a, &b, sizeof a) == 0; }

/* An orthogonal matrix: the identity rotated by Givens rotations in the planes (i, i+1). */
static inline void fill_orthogonal(size_t d, double *m, double phase) {
    size_t i, r;
    memset(m, 0, d * d * sizeof *m);
    for (i = 0; i < d; ++i) m[i * d + i] = 1.0;
    for (i = 0; i + 1 < d; ++i) {
        double a = 0.3 + phase + 0.17 * (double)i, c = cos(a), s = sin(a);
        for (r = 0; r < d; ++r) {
            double x = m[r * d + i], y = m[r * d + i + 1];
            m[r * d + i] = c * x - s * y;
            m[r * d + i + 1] = s * x + c * y;
        }
    }
}

static inline void normalize(double *v, size_t d) {
    double s = 0;
    size_t i;
    for (i = 0; i < d; ++i) s += v[i] * v[i];
    s = sqrt(s);
    for (i = 0; i < d; ++i) v[i] /= s;
}

/* A unit quaternion (d = 4) or complex number (d = 2) depending on `t`. */
static inline void unit_vector(size_t d, double t, double *out) {
    size_t i;
    for (i = 0; i < d; ++i) out[i] = sin(1.3 * (double)i + t) + (i == 0 ? 1.5 : 0.0);
    normalize(out, d);
}

/* "`<name>` is NULL" / "`<name>[<i>]`" (the entry of a non-finite value) */
static inline const char *null_needle(const char *name) {
    static char buf[64];
    snprintf(buf, sizeof buf, "`%s` is NULL", name);
    return buf;
}

static inline const char *entry_needle(const char *name, size_t i) {
    static char buf[64];
    snprintf(buf, sizeof buf, "`%s[%u]`", name, (unsigned)i);
    return buf;
}

/* max |P_a - P_b| / max(1, max |z_a|) with P = M diag(z) M^T (d = 4, row-major M). */
static inline double exponent_difference(const double *ma, const double *za, const double *mb, const double *zb) {
    double worst = 0, scale = 1;
    int r, c, k;
    for (k = 0; k < 4; ++k)
        if (fabs(za[k]) > scale) scale = fabs(za[k]);
    for (r = 0; r < 4; ++r)
        for (c = 0; c < 4; ++c) {
            double pa = 0, pb = 0;
            for (k = 0; k < 4; ++k) {
                pa += ma[r * 4 + k] * za[k] * ma[c * 4 + k];
                pb += mb[r * 4 + k] * zb[k] * mb[c * 4 + k];
            }
            if (fabs(pa - pb) > worst) worst = fabs(pa - pb);
        }
    return worst / scale;
}

#endif
