/*
 * bingham_eigen.hpp -- bingham.hpp with its Eigen overloads: includes <Eigen/Core> and
 * <Eigen/Geometry>, then bingham.hpp. SPDX-License-Identifier: MIT OR Apache-2.0
 *
 * Equivalent to including Eigen yourself before bingham.hpp. Include this header (not
 * bingham.hpp) first in every file that uses the Eigen overloads.
 */
#ifndef BINGHAM_EIGEN_HPP
#define BINGHAM_EIGEN_HPP

#if defined(BINGHAM_HPP) && !BINGHAM_HPP_EIGEN
#error "bingham.hpp was included before Eigen: include bingham_eigen.hpp (or <Eigen/Core> and <Eigen/Geometry>) first"
#endif

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "bingham.hpp"

#endif  // BINGHAM_EIGEN_HPP
