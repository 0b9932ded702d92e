/* Minimal test helpers for the C and C++ test programs in c_tests/ (built and run by
 * tests/c_tests.rs). Each CHECK counts; main() returns check_summary(). */
#ifndef BINGHAM_C_TESTS_CHECK_H
#define BINGHAM_C_TESTS_CHECK_H

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "bingham.h"

static int check_count = 0;
static int check_failures = 0;

static void check_report(int ok, const char *file, int line, const char *what) {
    ++check_count;
    if (!ok) {
        ++check_failures;
        char msg[512];
        size_t len = 0;
        bingham_last_error_message(msg, sizeof msg, &len);
        fprintf(stderr, "%s:%d: CHECK FAILED: %s\n    (last error message: \"%s\")\n", file, line,
                what, msg);
    }
}

#define CHECK(cond) check_report((cond) ? 1 : 0, __FILE__, __LINE__, #cond)

/* Expects `call` to return `expected`. */
#define CHECK_STATUS(call, expected)                                                            \
    do {                                                                                        \
        int check_st_ = (int)(call);                                                            \
        if (check_st_ != (int)(expected))                                                       \
            fprintf(stderr, "    got status %d (%s), expected %d\n", check_st_,                \
                    bingham_status_str(check_st_), (int)(expected));                            \
        check_report(check_st_ == (int)(expected), __FILE__, __LINE__, #call " == " #expected); \
    } while (0)

#define CHECK_OK(call) CHECK_STATUS(call, BINGHAM_OK)

/* |a - b| <= tol * max(1, |b|) */
#define CHECK_CLOSE(a, b, tol)                                                                  \
    do {                                                                                        \
        double check_a_ = (a), check_b_ = (b);                                                  \
        double check_s_ = fabs(check_b_) > 1.0 ? fabs(check_b_) : 1.0;                          \
        int check_ok_ = fabs(check_a_ - check_b_) <= (tol) * check_s_;                          \
        if (!check_ok_)                                                                         \
            fprintf(stderr, "    %.17g vs %.17g (diff %.3g, tol %.3g)\n", check_a_, check_b_,   \
                    check_a_ - check_b_, (double)(tol));                                        \
        check_report(check_ok_, __FILE__, __LINE__, #a " ~ " #b);                               \
    } while (0)

/* The calling thread's last error message (in a static buffer, overwritten by the next call). */
static inline const char *check_last_message(void) {
    static char buf[1024];
    size_t len = 0;
    bingham_last_error_message(buf, sizeof buf, &len);
    return buf;
}

/* After a failure of `fn`: the last message starts with "<fn>: " and contains `needle` (if not
 * NULL). Counts as one check, reported at the caller's line. */
#define CHECK_MESSAGE(fn, needle) check_message_at((fn), (needle), __FILE__, __LINE__)

static inline void check_message_at(const char *fn, const char *needle, const char *file, int line) {
    const char *msg = check_last_message();
    size_t nl = strlen(fn);
    int ok = strncmp(msg, fn, nl) == 0 && msg[nl] == ':' && (!needle || strstr(msg, needle));
    if (!ok)
        fprintf(stderr, "    message \"%s\" should name %s and contain \"%s\"\n", msg, fn,
                needle ? needle : "");
    check_report(ok, file, line, "last error message");
}

static int check_summary(const char *program) {
    if (check_failures == 0) {
        printf("%s: all %d checks passed\n", program, check_count);
        return 0;
    }
    printf("%s: %d of %d checks FAILED\n", program, check_failures, check_count);
    return 1;
}

#endif
