// The header compiles as C++11 (-std=c++11 -Wall -Wextra -Werror -pedantic), can be included
// twice, declares its functions with C linkage, and its constants agree with the library.
#include "bingham.h"
#include "bingham.h"

#include <cstdio>
#include <cstring>
#include <string>
#include <type_traits>

static_assert(BINGHAM_OK == 0, "BINGHAM_OK must be 0");
static_assert(BINGHAM_ERR_NULL_ARGUMENT == 1 && BINGHAM_ERR_INVALID_DIMENSION == 2 &&
                  BINGHAM_ERR_INVALID_ARGUMENT == 3 && BINGHAM_ERR_NOT_CONVERGED == 4 &&
                  BINGHAM_ERR_NUMERICAL == 5 && BINGHAM_ERR_PANIC == 6,
              "status values are part of the ABI");
static_assert(std::is_same<decltype(&bingham_mle),
                           bingham_status (*)(size_t, const double *, double *, double *)>::value,
              "bingham_mle signature");
static_assert(std::is_same<decltype(&bingham_sample),
                           bingham_status (*)(size_t, const double *, const double *, uint64_t, size_t,
                                              double *)>::value,
              "bingham_sample signature");
static_assert(BINGHAM_MIN_DIM == 2 && BINGHAM_MAX_DIM == 64, "dimension limits");

int main() {
    const std::string expect = std::to_string(BINGHAM_VERSION_MAJOR) + "." + std::to_string(BINGHAM_VERSION_MINOR) +
                               "." + std::to_string(BINGHAM_VERSION_PATCH);
    int failures = 0;
    if (expect != bingham_version()) {
        std::fprintf(stderr, "bingham_version() = %s, header says %s\n", bingham_version(), expect.c_str());
        ++failures;
    }
    const double z[3] = {-2.0, -1.0, 0.0};
    double log_f = 0.0;
    if (bingham_log_normalization_constant(3, z, &log_f, nullptr) != BINGHAM_OK) ++failures;
    if (bingham_log_normalization_constant(1, z, &log_f, nullptr) != BINGHAM_ERR_INVALID_DIMENSION) ++failures;
    char msg[256];
    std::size_t len = 0;
    if (bingham_last_error_message(msg, sizeof msg, &len) != BINGHAM_OK || len == 0) ++failures;
    if (std::strcmp(bingham_status_str(BINGHAM_ERR_INVALID_DIMENSION), "invalid dimension") != 0) ++failures;
    std::printf("header_cxx11: %s\n", failures ? "FAILED" : "ok");
    return failures ? 1 : 0;
}
