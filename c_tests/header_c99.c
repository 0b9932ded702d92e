/* The header compiles as strict C99 (-std=c99 -Wall -Wextra -Werror -pedantic
 * -Wstrict-prototypes), can be included twice, and its constants agree with the library. */
#include "bingham.h"
#include "bingham.h" /* the include guard makes a second inclusion harmless */

#include <stdio.h>
#include <string.h>

/* C99 has no _Static_assert: a negative array size fails compilation. */
typedef char assert_ok_is_zero[BINGHAM_OK == 0 ? 1 : -1];
typedef char assert_panic_is_six[BINGHAM_ERR_PANIC == 6 ? 1 : -1];
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
    printf("header_c99: %s\n", failures ? "FAILED" : "ok");
    return failures ? 1 : 0;
}
