#pragma once
/// Small-strain linear elastic law and its registry entry. In 2D plane strain (F33 = 1); tangent
/// convention of law.hpp: a_ijkl = c_ijkl + delta_ik sigma_jl.
#include "mpmcd/materials/lame_law.hpp"

namespace mpmcd::materials {

/// Small-strain linear elasticity used as Cauchy stress: sigma = lambda tr(eps) I + 2 mu eps,
/// eps = (F + F^T)/2 - I; its tangent follows from P = J sigma F^-T:
/// a_ijkl = sigma_ij d_kl + lambda d_ij F_lk + mu (d_ik F_lj + d_jk F_li) - sigma_il d_jk.
/// Not objective: meant for small rotations and verification only.
template <int Dim>
class LinearElastic final : public LameLaw<Dim> {
 public:
  static constexpr const char* kName = "linear_elastic";  ///< registry name
  using LameLaw<Dim>::LameLaw;
  std::string name() const override { return kName; }
  bool symmetric_tangent() const override { return false; }
  void evaluate(const LawBatch<Dim>& batch) const override {
    const double lambda = this->lambda_, mu = this->mu_;
    const std::size_t n = batch.F.size();
    for (std::size_t p = 0; p < n; ++p) {
      const Mat<Dim>& F = batch.F[p];
      const Mat<Dim> eps = 0.5 * (F + F.transpose()) - Mat<Dim>::Identity();
      const Mat<Dim> sigma = lambda * eps.trace() * Mat<Dim>::Identity() + 2.0 * mu * eps;
      batch.sigma[p] = sigma;
      if (!batch.sigma_zz.empty()) batch.sigma_zz[p] = lambda * eps.trace();  // eps33 = 0
      if (!batch.energy.empty())
        batch.energy[p] = 0.5 * lambda * eps.trace() * eps.trace() + mu * eps.squaredNorm();
      if (!batch.tangent.empty()) {
        // c = a - delta_ik sigma_jl with a from the derivative of P = J sigma F^-T
        fill_spatial_tangent<Dim>(batch.tangent[p], sigma, [&](int i, int j, int k, int l) {
          return sigma(i, j) * kron(k, l) + lambda * kron(i, j) * F(l, k) +
                 mu * (kron(i, k) * F(l, j) + kron(j, k) * F(l, i)) - sigma(i, l) * kron(j, k) -
                 kron(i, k) * sigma(j, l);
        });
      }
    }
  }
};

/// Registry entry of LinearElastic.
inline LawInfo linear_elastic_law() {
  return law_entry<LinearElastic>(
      "small-strain linear elasticity, sigma = lambda tr(eps) I + 2 mu eps, eps = sym(F) - I",
      lame_parameters("shear modulus, > 0"));
}

}  // namespace mpmcd::materials
