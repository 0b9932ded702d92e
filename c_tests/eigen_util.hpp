// Helpers shared by the Eigen-based C++ test programs (reference_eigen.cpp, filter_eigen.cpp,
// vector_eigen.cpp, deterministic_eigen.cpp, world_eigen.cpp): random test inputs from a
// caller-owned generator, row-major conversion, and the composition x (+) y written
// independently of the library (std::complex for d = 2, Eigen's quaternion product for d = 4).
// Header-only, C++11.
#ifndef BINGHAM_C_TESTS_EIGEN_UTIL_HPP
#define BINGHAM_C_TESTS_EIGEN_UTIL_HPP

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <complex>
#include <random>
#include <vector>

namespace eigen_util {

typedef Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> RowMatrix;

// A Haar-distributed orthogonal d x d matrix (Q of the QR of a Gaussian matrix).
inline Eigen::MatrixXd random_orthogonal(std::mt19937_64 &rng, int d) {
    std::normal_distribution<double> g;
    Eigen::MatrixXd a(d, d);
    for (int i = 0; i < d; ++i)
        for (int j = 0; j < d; ++j) a(i, j) = g(rng);
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(a);
    return qr.householderQ() * Eigen::MatrixXd::Identity(d, d);
}

// A uniformly distributed unit vector of length d.
inline Eigen::VectorXd random_unit(std::mt19937_64 &rng, int d) {
    std::normal_distribution<double> g;
    Eigen::VectorXd v(d);
    for (int i = 0; i < d; ++i) v(i) = g(rng);
    return v.normalized();
}

// Concentrations uniform in [lo, hi] with the last one 0.
inline Eigen::VectorXd random_z(std::mt19937_64 &rng, int d, double lo, double hi) {
    std::uniform_real_distribution<double> u(lo, hi);
    Eigen::VectorXd z(d);
    for (int i = 0; i < d; ++i) z(i) = u(rng);
    z(d - 1) = 0;
    return z;
}

inline std::vector<double> row_major(const Eigen::MatrixXd &m) {
    RowMatrix r = m;
    return std::vector<double>(r.data(), r.data() + r.size());
}

inline Eigen::MatrixXd from_row_major(const double *p, int d) {
    Eigen::MatrixXd m(d, d);
    for (int i = 0; i < d; ++i)
        for (int j = 0; j < d; ++j) m(i, j) = p[i * d + j];
    return m;
}

inline Eigen::MatrixXd from_row_major(const std::vector<double> &v, int d) { return from_row_major(v.data(), d); }

// x (+) y: complex multiplication (d = 2) or the Hamilton product (d = 4, scalar first).
inline Eigen::VectorXd compose_vectors(const Eigen::VectorXd &x, const Eigen::VectorXd &y) {
    Eigen::VectorXd r(x.size());
    if (x.size() == 2) {
        std::complex<double> p = std::complex<double>(x(0), x(1)) * std::complex<double>(y(0), y(1));
        r << p.real(), p.imag();
    } else {
        Eigen::Quaterniond p = Eigen::Quaterniond(x(0), x(1), x(2), x(3)) * Eigen::Quaterniond(y(0), y(1), y(2), y(3));
        r << p.w(), p.x(), p.y(), p.z();
    }
    return r;
}

inline double max_abs(const Eigen::MatrixXd &m) { return m.cwiseAbs().maxCoeff(); }

} // namespace eigen_util

#endif
