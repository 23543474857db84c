#pragma once
/// Constitutive-law interface (method.md §3) and the registry that creates laws by name.
/// A law is called once per batch of points (a grain), never per point through a virtual call.
/// A law is one header (its class and its registry entry) plus one line in
/// src/materials/registry.cpp: docs/architecture.md, "Adding a material law".
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "mpmcd/core/types.hpp"

namespace mpmcd::materials {

/// Inputs and outputs of one law evaluation over `F.size()` points (all spans have that length,
/// history spans have length n * history_size(); optional outputs may be empty spans).
template <int Dim>
struct LawBatch {
  std::span<const Mat<Dim>> F;          ///< deformation gradient F (plane strain: F33 = 1) [-]
  std::span<const double> history_old;  ///< committed history variables (law-specific units)
  std::span<double> history_new;        ///< trial history variables written by the law
  std::span<Mat<Dim>> sigma;            ///< out: Cauchy stress [Pa]
  std::span<Tensor4<Dim>> tangent;      ///< out (optional): spatial tangent a = c_mat + c_geo [Pa]
  std::span<double> energy;    ///< out (optional): stored energy per reference volume [J/m^3]
  std::span<double> sigma_zz;  ///< out (optional, 2D): out-of-plane Cauchy stress [Pa]
};

/// A constitutive law. The tangent returned is the spatial (Eulerian) tangent
///   a_ijkl = J^-1 F_jJ F_lL dP_iJ/dF_kL = c_ijkl + delta_ik sigma_jl,
/// i.e. the material tangent c (Lie derivative of Kirchhoff stress over J) plus the geometric term,
/// so that the nodal stiffness is K^{IJ}_ik = sum_p V_p dN_I/dx_j a_ijkl dN_J/dx_l (method.md §2).
template <int Dim>
class Law {
 public:
  virtual ~Law() = default;
  /// Registry name of the law.
  virtual std::string name() const = 0;
  /// Number of history doubles per point [-].
  virtual int history_size() const { return 0; }
  /// Writes the initial history of `n` points into `history` (length n * history_size()).
  virtual void init_history(std::span<double> history) const { (void)history; }
  /// Evaluates stress (and, if requested, tangent and energy) for a batch of points.
  virtual void evaluate(const LawBatch<Dim>& batch) const = 0;
  /// True if the tangent has major symmetry (a_ijkl = a_klij): symmetric solvers may be used.
  virtual bool symmetric_tangent() const { return true; }
  /// Small-strain P-wave modulus M (lambda + 2 mu for isotropic elasticity) [Pa], for wave-speed
  /// estimates and scaling (M_p of the compaction observables).
  virtual double wave_modulus() const = 0;
  /// Small-strain bulk modulus K, mean in-plane stress over area strain in 2D plane strain
  /// (lambda + mu), over volume strain in 3D (lambda + 2 mu / 3) [Pa] (K_p of the analysis).
  virtual double bulk_modulus() const = 0;
  /// Small-strain shear modulus mu [Pa].
  virtual double shear_modulus() const = 0;
};

/// Fills a_ijkl = c(i, j, k, l) + delta_ik sigma_jl: the material tangent `c` [Pa] plus the
/// geometric term (the convention of Law).
template <int Dim, class C>
void fill_spatial_tangent(Tensor4<Dim>& a, const Mat<Dim>& sigma, C&& c) {
  for (int i = 0; i < Dim; ++i)
    for (int j = 0; j < Dim; ++j)
      for (int k = 0; k < Dim; ++k)
        for (int l = 0; l < Dim; ++l)
          a(i * Dim + j, k * Dim + l) = c(i, j, k, l) + kron(i, k) * sigma(j, l);
}

/// A documented law parameter.
struct ParamSpec {
  std::string name;         ///< key in the [[materials]] table
  std::string unit;         ///< SI unit, e.g. "Pa"
  std::string description;  ///< one line
  double min = 0.0;         ///< smallest allowed value (inclusive)
  double max = 1e300;       ///< largest allowed value (inclusive)
};

/// A material's parameter values by ParamSpec name (units of the ParamSpecs).
using LawParams = std::map<std::string, double>;

/// Creates a law from parameters validated against its entry (every ParamSpec present, in range).
template <int Dim>
using LawFactory = std::unique_ptr<Law<Dim>> (*)(const LawParams& params);

/// Registry entry: a law's name, description, parameters (all required) and its factories. The
/// law it creates answers the moduli (Law::wave_modulus, bulk_modulus, shear_modulus), so that
/// nothing outside the law's own file names its parameters.
struct LawInfo {
  std::string name;                   ///< registry name, e.g. "neo_hookean"
  std::string description;            ///< one line, with the equation it implements
  std::vector<ParamSpec> params;      ///< its parameters
  LawFactory<2> create_2d = nullptr;  ///< creates the 2D (plane strain) law
  LawFactory<3> create_3d = nullptr;  ///< creates the 3D law

  /// The factory for dimension Dim.
  template <int Dim>
  LawFactory<Dim> factory() const {
    if constexpr (Dim == 2)
      return create_2d;
    else
      return create_3d;
  }
};

/// The entry of law class template `L` (L<Dim>::kName its name, L<Dim>(const LawParams&) its
/// constructor) with `description` and `params`.
template <template <int> class L>
LawInfo law_entry(std::string description, std::vector<ParamSpec> params) {
  return {L<2>::kName, std::move(description), std::move(params),
          [](const LawParams& p) -> std::unique_ptr<Law<2>> { return std::make_unique<L<2>>(p); },
          [](const LawParams& p) -> std::unique_ptr<Law<3>> { return std::make_unique<L<3>>(p); }};
}

/// All registered laws, in documentation order: the built-in laws (src/materials/registry.cpp),
/// then those added by register_law.
const std::vector<LawInfo>& law_registry();

/// Adds `law` to the registry (a test's or a tool's own law); call it before the first input is
/// read (the input schema lists the laws once). Throws std::invalid_argument if the name is taken.
void register_law(LawInfo law);

/// Creates law `name` with `params` (validated against the registry; throws InputError).
template <int Dim>
std::unique_ptr<Law<Dim>> make_law(const std::string& name, const LawParams& params);

}  // namespace mpmcd::materials
