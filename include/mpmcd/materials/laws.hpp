#pragma once
/// The elastic laws: compressible Neo-Hookean, Saint Venant-Kirchhoff, small-strain linear elastic.
/// In 2D all are plane strain (F33 = 1). Tangents follow the convention of law.hpp:
/// a_ijkl = c_ijkl + delta_ik sigma_jl, c the spatial material tangent.
#include <cmath>
#include <string>

#include "mpmcd/materials/law.hpp"

namespace mpmcd::materials {

/// Fills a_ijkl = c(i, j, k, l) + delta_ik sigma_jl: the material tangent `c` [Pa] plus the
/// geometric term (law.hpp convention).
template <int Dim, class C>
void fill_spatial_tangent(Tensor4<Dim>& a, const Mat<Dim>& sigma, C&& c) {
  for (int i = 0; i < Dim; ++i)
    for (int j = 0; j < Dim; ++j)
      for (int k = 0; k < Dim; ++k)
        for (int l = 0; l < Dim; ++l)
          a(i * Dim + j, k * Dim + l) = c(i, j, k, l) + kron(i, k) * sigma(j, l);
}

/// Compressible Neo-Hookean (paper eq. 8): S = (lambda ln J - mu) C^-1 + mu I, i.e. Kirchhoff
/// stress tau = mu (b - I) + lambda ln J I and c = (lambda/J) I x I + (2/J)(mu - lambda ln J) I^sym
/// (method.md §3); energy W = mu/2 (tr C - 3) - mu ln J + lambda/2 (ln J)^2.
template <int Dim>
class NeoHookean final : public Law<Dim> {
 public:
  /// `lambda`, `mu`: Lame coefficients [Pa].
  NeoHookean(double lambda, double mu) : lambda_(lambda), mu_(mu) {}
  std::string name() const override { return "neo_hookean"; }
  double wave_modulus() const override { return lambda_ + 2.0 * mu_; }
  double shear_modulus() const override { return mu_; }
  void evaluate(const LawBatch<Dim>& batch) const override {
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
          (mu_ * (b - Mat<Dim>::Identity()) + lambda_ * lnJ * Mat<Dim>::Identity()) / J;
      batch.sigma[p] = sigma;
      if (!batch.sigma_zz.empty()) batch.sigma_zz[p] = lambda_ * lnJ / J;  // b33 = 1
      if (want_energy)
        batch.energy[p] = 0.5 * mu_ * (b.trace() - Dim) - mu_ * lnJ + 0.5 * lambda_ * lnJ * lnJ;
      if (want_tangent) {
        const double a1 = lambda_ / J;                // coefficient of delta_ij delta_kl
        const double a2 = (mu_ - lambda_ * lnJ) / J;  // coefficient of (d_ik d_jl + d_il d_jk)
        fill_spatial_tangent<Dim>(batch.tangent[p], sigma, [&](int i, int j, int k, int l) {
          return a1 * kron(i, j) * kron(k, l) +
                 a2 * (kron(i, k) * kron(j, l) + kron(i, l) * kron(j, k));
        });
      }
    }
  }

 private:
  double lambda_, mu_;
};

/// Saint Venant-Kirchhoff: S = lambda tr(E) I + 2 mu E, E = (C - I)/2, sigma = F S F^T / J;
/// c_ijkl = J^-1 [lambda b_ij b_kl + mu (b_ik b_jl + b_il b_jk)]; W = lambda/2 tr(E)^2 + mu E:E.
template <int Dim>
class SaintVenantKirchhoff final : public Law<Dim> {
 public:
  /// `lambda`, `mu`: Lame coefficients [Pa].
  SaintVenantKirchhoff(double lambda, double mu) : lambda_(lambda), mu_(mu) {}
  std::string name() const override { return "saint_venant_kirchhoff"; }
  double wave_modulus() const override { return lambda_ + 2.0 * mu_; }
  double shear_modulus() const override { return mu_; }
  void evaluate(const LawBatch<Dim>& batch) const override {
    const std::size_t n = batch.F.size();
    for (std::size_t p = 0; p < n; ++p) {
      const Mat<Dim>& F = batch.F[p];
      const double J = F.determinant();
      const Mat<Dim> E = 0.5 * (F.transpose() * F - Mat<Dim>::Identity());
      const Mat<Dim> S = lambda_ * E.trace() * Mat<Dim>::Identity() + 2.0 * mu_ * E;
      const Mat<Dim> sigma = F * S * F.transpose() / J;
      batch.sigma[p] = sigma;
      if (!batch.sigma_zz.empty()) batch.sigma_zz[p] = lambda_ * E.trace() / J;  // E33 = 0
      if (!batch.energy.empty())
        batch.energy[p] = 0.5 * lambda_ * E.trace() * E.trace() + mu_ * E.squaredNorm();
      if (!batch.tangent.empty()) {
        const Mat<Dim> b = F * F.transpose();
        fill_spatial_tangent<Dim>(batch.tangent[p], sigma, [&](int i, int j, int k, int l) {
          return (lambda_ * b(i, j) * b(k, l) + mu_ * (b(i, k) * b(j, l) + b(i, l) * b(j, k))) / J;
        });
      }
    }
  }

 private:
  double lambda_, mu_;
};

/// Small-strain linear elasticity used as Cauchy stress: sigma = lambda tr(eps) I + 2 mu eps,
/// eps = (F + F^T)/2 - I; its tangent follows from P = J sigma F^-T:
/// a_ijkl = sigma_ij d_kl + lambda d_ij F_lk + mu (d_ik F_lj + d_jk F_li) - sigma_il d_jk.
/// Not objective: meant for small rotations and verification only.
template <int Dim>
class LinearElastic final : public Law<Dim> {
 public:
  /// `lambda`, `mu`: Lame coefficients [Pa].
  LinearElastic(double lambda, double mu) : lambda_(lambda), mu_(mu) {}
  std::string name() const override { return "linear_elastic"; }
  double wave_modulus() const override { return lambda_ + 2.0 * mu_; }
  double shear_modulus() const override { return mu_; }
  bool symmetric_tangent() const override { return false; }
  void evaluate(const LawBatch<Dim>& batch) const override {
    const std::size_t n = batch.F.size();
    for (std::size_t p = 0; p < n; ++p) {
      const Mat<Dim>& F = batch.F[p];
      const Mat<Dim> eps = 0.5 * (F + F.transpose()) - Mat<Dim>::Identity();
      const Mat<Dim> sigma = lambda_ * eps.trace() * Mat<Dim>::Identity() + 2.0 * mu_ * eps;
      batch.sigma[p] = sigma;
      if (!batch.sigma_zz.empty()) batch.sigma_zz[p] = lambda_ * eps.trace();  // eps33 = 0
      if (!batch.energy.empty())
        batch.energy[p] = 0.5 * lambda_ * eps.trace() * eps.trace() + mu_ * eps.squaredNorm();
      if (!batch.tangent.empty()) {
        // c = a - delta_ik sigma_jl with a from the derivative of P = J sigma F^-T
        fill_spatial_tangent<Dim>(batch.tangent[p], sigma, [&](int i, int j, int k, int l) {
          return sigma(i, j) * kron(k, l) + lambda_ * kron(i, j) * F(l, k) +
                 mu_ * (kron(i, k) * F(l, j) + kron(j, k) * F(l, i)) - sigma(i, l) * kron(j, k) -
                 kron(i, k) * sigma(j, l);
        });
      }
    }
  }

 private:
  double lambda_, mu_;
};

}  // namespace mpmcd::materials
