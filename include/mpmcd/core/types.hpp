#pragma once
/// Fixed-size linear-algebra types shared by every module; the dimension is a template parameter.
#include <Eigen/Dense>
#include <cstdint>

namespace mpmcd {

/// Spatial vector in Dim dimensions [units of the quantity it holds].
template <int Dim>
using Vec = Eigen::Matrix<double, Dim, 1>;
/// Second-order tensor in Dim dimensions, row i column j = component ij.
template <int Dim>
using Mat = Eigen::Matrix<double, Dim, Dim>;
/// Fourth-order tensor stored as a (Dim*Dim)x(Dim*Dim) matrix: T(ij, kl) with ij = i*Dim + j.
template <int Dim>
using Tensor4 = Eigen::Matrix<double, Dim * Dim, Dim * Dim>;
/// Integer grid coordinates of a node or cell [-].
template <int Dim>
using IVec = Eigen::Matrix<std::int64_t, Dim, 1>;

/// Flat index of component (i, j) in a Tensor4 row or column.
template <int Dim>
constexpr int pair_index(int i, int j) {
  return i * Dim + j;
}

/// Kronecker delta.
constexpr double kron(int i, int j) {
  return i == j ? 1.0 : 0.0;
}

}  // namespace mpmcd
