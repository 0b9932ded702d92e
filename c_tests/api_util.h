/* Helpers shared by the C API tests spin_api.c (the spin filter handle) and world_api.c (the
 * world-frame steps of the filter handle): input arrays placed flush against an inaccessible page,
 * test matrices and unit vectors, the expected message fragments, and the distance between two
 * Bingham exponents. Include after check.h, with _DEFAULT_SOURCE defined before any #include
 * (for MAP_ANONYMOUS under -std=c99); call guard_pages_init() first in main(). */
#ifndef BINGHAM_C_TESTS_API_UTIL_H
#define BINGHAM_C_TESTS_API_UTIL_H

#ifndef _DEFAULT_SOURCE
#error "define _DEFAULT_SOURCE before any #include"
#endif

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

static unsigned char *guard_pages; /* [readable page][PROT_NONE page] */
static size_t page_size;

/* A copy of src[0..n) ending exactly at an inaccessible page: reading past n crashes. There is
 * one such buffer: pass at most one flush() result per call. */
static inline double *flush(const double *src, size_t n) {
    double *p = (double *)(guard_pages + page_size) - n;
    memcpy(p, src, n * sizeof(double));
    return p;
}

static inline double *no_access(void) { return (double *)(guard_pages + page_size); }

/* Maps guard_pages and makes its second page inaccessible; 0 on success, else 1 (with perror). */
static inline int guard_pages_init(void) {
    long ps = sysconf(_SC_PAGESIZE);
    page_size = ps > 0 ? (size_t)ps : 4096;
    guard_pages = mmap(NULL, 2 * page_size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (guard_pages == MAP_FAILED || mprotect(guard_pages + page_size, page_size, PROT_NONE)) {
        perror("mmap/mprotect");
        return 1;
    }
    return 0;
}

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
