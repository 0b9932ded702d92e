// standards: c++17 c++20
// examples/c/tracking_plain.c with the C++ wrapper and Eigen (same scenario, same numbers).
#include <bingham_eigen.hpp>
#include <cmath>
#include <cstdio>

int main() try {
    const int steps = 2000, fix_every = 10;
    const double deg = 180 / 3.14159265358979323846;
    const Eigen::Vector3d omega(0.5, -0.3, 1.2);  // rad/s, body frame
    const auto w = bingham::noise_from_angle_std_deg(4, 0.2), v = bingham::noise_from_angle_std_deg(4, 3.0);
    const auto gyro_noise = bingham::sample(w, steps, 1), fix_noise = bingham::sample(v, steps / fix_every, 2);
    const auto noise = [](const std::vector<double> &s, int k) { return bingham::Quaternion::from_array(&s[4 * k]); };
    const Eigen::Quaterniond inc(Eigen::AngleAxisd(omega.norm() * 0.01, omega.normalized()));
    bingham::Filter filter(bingham::noise_from_angle_std_deg(4, 10.0));
    Eigen::Quaterniond truth = Eigen::Quaterniond::Identity();
    double sum_sq = 0;
    for (int k = 0; k < steps; ++k) {
        truth = truth * inc;
        filter.predict_rotation(inc * Eigen::Quaterniond(noise(gyro_noise, k)), w);
        if ((k + 1) % fix_every == 0) filter.update(truth * Eigen::Quaterniond(noise(fix_noise, k / fix_every)), v);
        const double e = Eigen::Quaterniond(filter.mode_quaternion()).angularDistance(truth) * deg;
        sum_sq += e * e;
    }
    std::printf("Gyroscope + fixes at 100 Hz, C++ wrapper: RMS error %.3f deg over %d steps; final spread %.3f deg\n",
                std::sqrt(sum_sq / steps), steps, filter.uncertainty() * deg);
} catch (const bingham::Error &e) {
    std::fprintf(stderr, "bingham: %s\n", e.what());
    return 1;
}
