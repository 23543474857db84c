#pragma once
/// Saint Venant-Kirchhoff law and its registry entry. In 2D plane strain (F33 = 1); tangent
/// convention of law.hpp: a_ijkl = c_ijkl + delta_ik sigma_jl.
#include "mpmcd/materials/lame_law.hpp"

namespace mpmcd::materials {

/// Saint Venant-Kirchhoff: S = lambda tr(E) I + 2 mu E, E = (C - I)/2, sigma = F S F^T / J;
/// c_ijkl = J^-1 [lambda b_ij b_kl + mu (b_ik b_jl + b_il b_jk)]; W = lambda/2 tr(E)^2 + mu E:E.
template <int Dim>
class SaintVenantKirchhoff final : public LameLaw<Dim> {
 public:
  static constexpr const char* kName = "saint_venant_kirchhoff";  ///< registry name
  using LameLaw<Dim>::LameLaw;
  std::string name() const override { return kName; }
  void evaluate(const LawBatch<Dim>& batch) const override {
    const double lambda = this->lambda_, mu = this->mu_;
    const std::size_t n = batch.F.size();
    for (std::size_t p = 0; p < n; ++p) {
      const Mat<Dim>& F = batch.F[p];
      const double J = F.determinant();
      const Mat<Dim> E = 0.5 * (F.transpose() * F - Mat<Dim>::Identity());
      const Mat<Dim> S = lambda * E.trace() * Mat<Dim>::Identity() + 2.0 * mu * E;
      const Mat<Dim> sigma = F * S * F.transpose() / J;
      batch.sigma[p] = sigma;
      if (!batch.sigma_zz.empty()) batch.sigma_zz[p] = lambda * E.trace() / J;  // E33 = 0
      if (!batch.energy.empty())
        batch.energy[p] = 0.5 * lambda * E.trace() * E.trace() + mu * E.squaredNorm();
      if (!batch.tangent.empty()) {
        const Mat<Dim> b = F * F.transpose();
        fill_spatial_tangent<Dim>(batch.tangent[p], sigma, [&](int i, int j, int k, int l) {
          return (lambda * b(i, j) * b(k, l) + mu * (b(i, k) * b(j, l) + b(i, l) * b(j, k))) / J;
        });
      }
    }
  }
};

/// Registry entry of SaintVenantKirchhoff.
inline LawInfo saint_venant_kirchhoff_law() {
  return law_entry<SaintVenantKirchhoff>(
      "Saint Venant-Kirchhoff, S = lambda tr(E) I + 2 mu E, E = (C - I)/2",
      lame_parameters("shear modulus, > 0"));
}

}  // namespace mpmcd::materials
