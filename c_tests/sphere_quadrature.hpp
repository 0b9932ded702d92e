// Brute-force quadrature on S^1, S^2, S^3 for the Eigen-based reference programs
// (reference_eigen.cpp, filter_eigen.cpp, world_eigen.cpp): Gauss-Legendre in the polar angles,
// trapezoid in the last angle (trapezoid alone on the circle), surface measure. Independent of
// the library.
#ifndef BINGHAM_C_TESTS_SPHERE_QUADRATURE_HPP
#define BINGHAM_C_TESTS_SPHERE_QUADRATURE_HPP

#include <Eigen/Dense>
#include <cmath>
#include <vector>

static const double PI = 3.14159265358979323846;

// ---- quadrature on the sphere -------------------------------------------------------------

struct Node {
    Eigen::VectorXd x;
    double w;
};

// x^T A x and S += e x x^T without Eigen temporaries: the quadrature loops run 10^5 to 10^6
// times per reference, and a dynamic-size temporary is a heap allocation per node, which
// dominated the programs' run time under AddressSanitizer (its allocator is slow by design).
template <class MA, class VX>
static inline double quad_form(const Eigen::MatrixBase<MA> &A, const Eigen::MatrixBase<VX> &x) {
    double q = 0;
    for (Eigen::Index j = 0; j < x.size(); ++j) {
        double c = 0;
        for (Eigen::Index i = 0; i < x.size(); ++i) c += A(i, j) * x(i);
        q += c * x(j);
    }
    return q;
}

template <class MS, class VY>
static inline void add_outer(Eigen::MatrixBase<MS> &S, double e, const Eigen::MatrixBase<VY> &y) {
    for (Eigen::Index j = 0; j < y.size(); ++j) {
        double c = e * y(j);
        for (Eigen::Index i = 0; i < y.size(); ++i) S(i, j) += c * y(i);
    }
}

// Gauss-Legendre nodes and weights on [a, b].
static void gauss_legendre(int n, double a, double b, std::vector<double> &t, std::vector<double> &w) {
    t.assign(n, 0.0);
    w.assign(n, 0.0);
    for (int i = 0; i < n; ++i) {
        double x = std::cos(PI * (i + 0.75) / (n + 0.5)), dp = 0;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1, p1 = x;
            for (int k = 2; k <= n; ++k) {
                double p2 = ((2 * k - 1) * x * p1 - (k - 1) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (x * p1 - p0) / (x * x - 1);
            double dx = p1 / dp;
            x -= dx;
            if (std::fabs(dx) < 1e-16) break;
        }
        t[i] = 0.5 * (a + b) + 0.5 * (b - a) * x;
        w[i] = (b - a) / ((1 - x * x) * dp * dp);
    }
}

// Nodes and weights of the surface measure on S^{d-1}, d = 2, 3, 4.
static std::vector<Node> sphere_nodes(int d, int n) {
    std::vector<Node> nodes;
    std::vector<double> t, w;
    gauss_legendre(n, 0, PI, t, w);
    int nphi = 2 * n;
    double hphi = 2 * PI / nphi;
    if (d == 2) {
        for (int k = 0; k < 4 * n; ++k) {
            double p = 2 * PI * k / (4 * n);
            Eigen::VectorXd x(2);
            x << std::cos(p), std::sin(p);
            nodes.push_back(Node{x, 2 * PI / (4 * n)});
        }
    } else if (d == 3) {
        for (int i = 0; i < n; ++i)
            for (int k = 0; k < nphi; ++k) {
                double th = t[i], p = k * hphi;
                Eigen::VectorXd x(3);
                x << std::cos(th), std::sin(th) * std::cos(p), std::sin(th) * std::sin(p);
                nodes.push_back(Node{x, w[i] * std::sin(th) * hphi});
            }
    } else {
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j)
                for (int k = 0; k < nphi; ++k) {
                    double ps = t[i], th = t[j], p = k * hphi;
                    Eigen::VectorXd x(4);
                    x << std::cos(ps), std::sin(ps) * std::cos(th), std::sin(ps) * std::sin(th) * std::cos(p),
                        std::sin(ps) * std::sin(th) * std::sin(p);
                    nodes.push_back(Node{x, w[i] * w[j] * std::sin(ps) * std::sin(ps) * std::sin(th) * hphi});
                }
    }
    return nodes;
}

#endif
