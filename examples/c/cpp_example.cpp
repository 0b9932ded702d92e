// Using the bingham C API from C++11: a small RAII-free wrapper that turns statuses into
// exceptions. Built by `make demo` and, against an installed copy found with pkg-config, by
// `make install-test`:
//
//   c++ -std=c++11 cpp_example.cpp $(pkg-config --cflags --libs bingham) -o cpp_example
#include <bingham.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

void check(bingham_status st) {
    if (st == BINGHAM_OK) return;
    std::size_t len = 0;
    bingham_last_error_message(nullptr, 0, &len);
    std::string msg(len + 1, '\0');
    bingham_last_error_message(&msg[0], msg.size(), &len);
    msg.resize(len);
    throw std::runtime_error(msg + " [" + bingham_status_str(st) + "]");
}

struct Bingham {
    std::size_t d;
    std::vector<double> m;  // row-major d x d, columns = principal directions, last = mode
    std::vector<double> z;  // ascending, last = 0
};

Bingham fit(const std::vector<double> &s, std::size_t d) {
    Bingham b{d, std::vector<double>(d * d), std::vector<double>(d)};
    check(bingham_mle(d, s.data(), b.m.data(), b.z.data()));
    return b;
}

}  // namespace

int main() {
    std::printf("The C API from C++11 (bingham %s): a d = 2 MLE round trip and an error as an exception\n",
                bingham_version());
    // A d = 2 (axis / complex number) distribution around (cos 0.3, sin 0.3).
    const double c = std::cos(0.3), s = std::sin(0.3);
    const std::vector<double> m = {-s, c, c, s};  // columns: (-s, c) and the mode (c, s)
    const std::vector<double> z = {-8.0, 0.0};
    std::vector<double> moment(4);
    check(bingham_second_moment(2, m.data(), z.data(), moment.data()));
    Bingham b = fit(moment, 2);
    std::printf("  MLE round trip: z = (%.12f, %.1f), mode = (%.12f, %.12f)\n", b.z[0], b.z[1], b.m[1], b.m[3]);
    if (std::fabs(b.z[0] + 8.0) > 1e-8 || std::fabs(std::fabs(b.m[1] * c + b.m[3] * s) - 1.0) > 1e-10) {
        std::fprintf(stderr, "round trip failed\n");
        return 1;
    }
    try {
        fit({1.0, 2.0, 0.0, 1.0}, 2);  // not symmetric
        std::fprintf(stderr, "expected an error\n");
        return 1;
    } catch (const std::runtime_error &e) {
        std::printf("  as expected: %s\n", e.what());
    }
    return 0;
}
