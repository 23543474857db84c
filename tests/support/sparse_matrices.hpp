#pragma once
// Synthetic sparse symmetric matrices shared by the TreeLdlt and SupernodalLlt unit tests and
// bench_contact.
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

// A symmetric positive semi-definite matrix like a dense 3D packing's W: `groups` grains in a
// row, each with `per_group` contacts of its own and `shared` more shared with the next grain;
// every pair of contacts of one grain couples, by a random Gram matrix of rank `rank` (entries
// v_i . v_j, v in [-1, 1]^rank), plus `diag` on the diagonal. Its factor's columns are long
// (about per_group + 2 shared entries), the case of the supernodal factorisation.
inline Eigen::SparseMatrix<double> grain_blocks_matrix(int groups, int per_group, int shared,
                                                       int rank, double diag, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int stride = per_group + shared, n = groups * stride;
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i) t.emplace_back(i, i, diag);
  for (int g = 0; g < groups; ++g) {
    std::vector<int> members;
    for (int k = 0; k < stride; ++k) members.push_back(g * stride + k);  // own, then shared
    if (g > 0)
      for (int k = per_group; k < stride; ++k) members.push_back((g - 1) * stride + k);
    std::vector<std::vector<double>> v(members.size(), std::vector<double>(rank));
    for (auto& vi : v)
      for (double& x : vi) x = u(rng);
    for (std::size_t a = 0; a < members.size(); ++a)
      for (std::size_t b = 0; b < members.size(); ++b) {
        double dot = 0;
        for (int r = 0; r < rank; ++r) dot += v[a][r] * v[b][r];
        t.emplace_back(members[a], members[b], dot);
      }
  }
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

}  // namespace mpmcd::test_support
