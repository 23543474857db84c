#pragma once
/// The base of the isotropic laws given by their Lame coefficients lambda and mu: their two
/// parameters and their small-strain moduli, declared once for Neo-Hookean, Saint Venant-Kirchhoff
/// and linear elasticity.
#include <string>
#include <vector>

#include "mpmcd/materials/law.hpp"

namespace mpmcd::materials {

/// The parameters `lambda` and `mu` [Pa]; `mu_description` documents mu.
inline std::vector<ParamSpec> lame_parameters(std::string mu_description) {
  return {{"lambda", "Pa", "first Lame coefficient", 0.0, 1e300},
          {"mu", "Pa", std::move(mu_description), 1e-300, 1e300}};
}

/// A law with Lame coefficients lambda, mu [Pa] and their small-strain moduli.
template <int Dim>
class LameLaw : public Law<Dim> {
 public:
  /// `lambda`, `mu`: Lame coefficients [Pa].
  LameLaw(double lambda, double mu) : lambda_(lambda), mu_(mu) {}
  /// From the parameters of lame_parameters.
  explicit LameLaw(const LawParams& params) : LameLaw(params.at("lambda"), params.at("mu")) {}
  double wave_modulus() const override { return lambda_ + 2.0 * mu_; }
  double bulk_modulus() const override { return lambda_ + 2.0 * mu_ / Dim; }
  double shear_modulus() const override { return mu_; }

 protected:
  double lambda_, mu_;
};

}  // namespace mpmcd::materials
