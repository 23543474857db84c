#pragma once
// A test-only law written by the recipe of docs/architecture.md ("Adding a material law"): its
// class and its registry entry in one file, parameters that are not lambda and mu. Tests register
// it with materials::register_law (tests/unit/materials/test_law_recipe.cpp, tests/unit/app).
#include <cmath>

#include "mpmcd/materials/law.hpp"

namespace mpmcd::test {

/// Neo-Hookean with a quadratic volumetric energy, W = G/2 (tr C - 3) - G ln J + kappa/2 (J - 1)^2:
/// tau = G (b - I) + kappa J (J - 1) I, c = kappa (2J - 1) I x I + (2/J)(G - kappa J (J - 1))
/// I^sym. Small strains: lambda = kappa, mu = G.
template <int Dim>
class QuadraticVolume final : public materials::Law<Dim> {
 public:
  static constexpr const char* kName = "test_quadratic_volume";  ///< registry name
  /// From the parameters `G`, `kappa` [Pa] of the entry below.
  explicit QuadraticVolume(const materials::LawParams& p) : g_(p.at("G")), kappa_(p.at("kappa")) {}
  std::string name() const override { return kName; }
  double wave_modulus() const override { return kappa_ + 2.0 * g_; }
  double bulk_modulus() const override { return kappa_ + 2.0 * g_ / Dim; }
  double shear_modulus() const override { return g_; }
  void evaluate(const materials::LawBatch<Dim>& batch) const override {
    for (std::size_t p = 0; p < batch.F.size(); ++p) {
      const Mat<Dim>& F = batch.F[p];
      const double J = F.determinant();
      const Mat<Dim> b = F * F.transpose();
      const Mat<Dim> sigma =
          (g_ * (b - Mat<Dim>::Identity()) + kappa_ * J * (J - 1) * Mat<Dim>::Identity()) / J;
      batch.sigma[p] = sigma;
      if (!batch.sigma_zz.empty()) batch.sigma_zz[p] = kappa_ * (J - 1);  // b33 = 1
      if (!batch.energy.empty())
        batch.energy[p] =
            0.5 * g_ * (b.trace() - Dim) - g_ * std::log(J) + 0.5 * kappa_ * (J - 1) * (J - 1);
      if (!batch.tangent.empty()) {
        const double a1 = kappa_ * (2 * J - 1);             // coefficient of d_ij d_kl
        const double a2 = (g_ - kappa_ * J * (J - 1)) / J;  // of (d_ik d_jl + d_il d_jk)
        materials::fill_spatial_tangent<Dim>(
            batch.tangent[p], sigma, [&](int i, int j, int k, int l) {
              return a1 * kron(i, j) * kron(k, l) +
                     a2 * (kron(i, k) * kron(j, l) + kron(i, l) * kron(j, k));
            });
      }
    }
  }

 private:
  double g_, kappa_;
};

/// Registry entry of QuadraticVolume.
inline materials::LawInfo quadratic_volume_law() {
  return materials::law_entry<QuadraticVolume>(
      "test only: Neo-Hookean with W_vol = kappa/2 (J - 1)^2",
      {{"G", "Pa", "shear modulus, > 0", 1e-300, 1e300},
       {"kappa", "Pa", "volumetric modulus", 0.0, 1e300}});
}

}  // namespace mpmcd::test
