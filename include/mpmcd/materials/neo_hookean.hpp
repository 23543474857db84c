#pragma once
/// Compressible Neo-Hookean law (paper eq. 8) and its registry entry. In 2D plane strain (F33 = 1);
/// tangent convention of law.hpp: a_ijkl = c_ijkl + delta_ik sigma_jl.
#include <cmath>

#include "mpmcd/materials/lame_law.hpp"

namespace mpmcd::materials {

/// Compressible Neo-Hookean (paper eq. 8): S = (lambda ln J - mu) C^-1 + mu I, i.e. Kirchhoff
/// stress tau = mu (b - I) + lambda ln J I and c = (lambda/J) I x I + (2/J)(mu - lambda ln J) I^sym
/// (method.md §3); energy W = mu/2 (tr C - 3) - mu ln J + lambda/2 (ln J)^2.
template <int Dim>
class NeoHookean final : public LameLaw<Dim> {
 public:
  static constexpr const char* kName = "neo_hookean";  ///< registry name
  using LameLaw<Dim>::LameLaw;
  std::string name() const override { return kName; }
  void evaluate(const LawBatch<Dim>& batch) const override {
    const double lambda = this->lambda_, mu = this->mu_;
    const std::size_t n = batch.F.size();
    const bool want_tangent = !batch.tangent.empty();
    const bool want_energy = !batch.energy.empty();
    for (std::size_t p = 0; p < n; ++p) {
      const Mat<Dim>& F = batch.F[p];
      const double J = F.determinant();
      const double lnJ = std::log(J);
      const Mat<Dim> b = F * F.transpose();
      // sigma = [mu (b - I) + lambda ln J I] / J   (method.md §3, Kirchhoff form of eq. 8)
      const Mat<Dim> sigma =
          (mu * (b - Mat<Dim>::Identity()) + lambda * lnJ * Mat<Dim>::Identity()) / J;
      batch.sigma[p] = sigma;
      if (!batch.sigma_zz.empty()) batch.sigma_zz[p] = lambda * lnJ / J;  // b33 = 1
      if (want_energy)
        batch.energy[p] = 0.5 * mu * (b.trace() - Dim) - mu * lnJ + 0.5 * lambda * lnJ * lnJ;
      if (want_tangent) {
        const double a1 = lambda / J;               // coefficient of delta_ij delta_kl
        const double a2 = (mu - lambda * lnJ) / J;  // coefficient of (d_ik d_jl + d_il d_jk)
        fill_spatial_tangent<Dim>(batch.tangent[p], sigma, [&](int i, int j, int k, int l) {
          return a1 * kron(i, j) * kron(k, l) +
                 a2 * (kron(i, k) * kron(j, l) + kron(i, l) * kron(j, k));
        });
      }
    }
  }
};

/// Registry entry of NeoHookean.
inline LawInfo neo_hookean_law() {
  return law_entry<NeoHookean>(
      "compressible Neo-Hookean, S = (lambda ln J - mu) C^-1 + mu I (paper eq. 8)",
      lame_parameters("shear modulus (second Lame coefficient), > 0"));
}

}  // namespace mpmcd::materials
