#pragma once
// A synthetic sparse symmetric matrix shared by the TreeLdlt unit test and bench_contact.
#include <Eigen/SparseCore>
#include <random>
#include <vector>

namespace mpmcd::test_support {

// A symmetric positive semi-definite matrix with the graph of an nx x ny grid with diagonals (a
// Delassus-like pattern): a sum of random rank-one couplings of neighbours (weights in
// [0.1, 1], random signs), plus `diag` on the diagonal.
inline Eigen::SparseMatrix<double> grid_matrix(int nx, int ny, double diag, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.1, 1.0);
  std::vector<Eigen::Triplet<double>> t;
  const auto id = [&](int i, int j) { return i * ny + j; };
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) {
      t.emplace_back(id(i, j), id(i, j), diag);
      const int di[] = {1, 0, 1, 1}, dj[] = {0, 1, 1, -1};
      for (int e = 0; e < 4; ++e) {
        const int a = i + di[e], b = j + dj[e];
        if (a >= nx || b < 0 || b >= ny) continue;
        const double w = u(rng), s = u(rng) > 0.5 ? 1.0 : -1.0;
        t.emplace_back(id(i, j), id(i, j), w);
        t.emplace_back(id(a, b), id(a, b), w);
        t.emplace_back(id(i, j), id(a, b), s * w);
        t.emplace_back(id(a, b), id(i, j), s * w);
      }
    }
  Eigen::SparseMatrix<double> A(nx * ny, nx * ny);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

}  // namespace mpmcd::test_support
