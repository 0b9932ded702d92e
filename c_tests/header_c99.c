/* The header compiles as strict C99 (-std=c99 -Wall -Wextra -Werror -pedantic
 * -Wstrict-prototypes), can be included twice, and its constants agree with the library. */
#include "bingham.h"
#include "bingham.h" /* the include guard makes a second inclusion harmless */

#include <stdio.h>
#include <string.h>

/* C99 has no _Static_assert: a negative array size fails compilation. */
typedef char assert_ok_is_zero[BINGHAM_OK == 0 ? 1 : -1];
typedef char assert_panic_is_six[BINGHAM_ERR_PANIC == 6 ? 1 : -1];
typedef char assert_callback_is_seven[BINGHAM_ERR_CALLBACK == 7 ? 1 : -1];
typedef char assert_sample_schemes[BINGHAM_SAMPLES_TAC2016 == 0 && BINGHAM_SAMPLES_MOMENTS == 1 ? 1 : -1];

/* The callback types accept plain C functions of the documented signatures. */
static int keep_transition(const double *x_in, double *x_out, void *user_data) {
    (void)x_in;
    (void)x_out;
    (void)user_data;
    return 1;
}
static int keep_log_likelihood(const double *x, double *log_l, void *user_data) {
    (void)x;
    (void)log_l;
    (void)user_data;
    return 1;
}
typedef char assert_size_t_dims[sizeof(size_t) >= 4 ? 1 : -1];

int main(void) {
    char expect[64];
    bingham_status st = BINGHAM_OK;
    size_t len = 0;
    double z[2] = {-1.0, 0.0}, f = 0.0;
    int failures = 0;
    snprintf(expect, sizeof expect, "%d.%d.%d", (int)BINGHAM_VERSION_MAJOR, (int)BINGHAM_VERSION_MINOR,
             (int)BINGHAM_VERSION_PATCH);
    if (strcmp(bingham_version(), expect) != 0) {
        fprintf(stderr, "bingham_version() = %s, header says %s\n", bingham_version(), expect);
        ++failures;
    }
    st = bingham_normalization_constant(2, z, &f, NULL);
    if (st != BINGHAM_OK || !(f > 0.0)) ++failures;
    if (bingham_last_error_message(NULL, 0, &len) != BINGHAM_OK) ++failures;
    if (strcmp(bingham_status_str((int)st), "ok") != 0) ++failures;
    {
        bingham_transition_fn a = keep_transition;
        bingham_log_likelihood_fn l = keep_log_likelihood;
        size_t n = 0;
        /* a NULL filter is refused before any callback */
        if (bingham_filter_predict_nonlinear(NULL, a, NULL, NULL, NULL) != BINGHAM_ERR_NULL_ARGUMENT) ++failures;
        if (bingham_filter_update_nonlinear(NULL, l, NULL) != BINGHAM_ERR_NULL_ARGUMENT) ++failures;
        if (bingham_deterministic_sample_count(4, BINGHAM_SAMPLES_MOMENTS, &n) != BINGHAM_OK || n != 19) ++failures;
        if (strcmp(bingham_status_str(BINGHAM_ERR_CALLBACK), "callback failed") != 0) ++failures;
    }
    printf("header_c99: %s\n", failures ? "FAILED" : "ok");
    return failures ? 1 : 0;
}
