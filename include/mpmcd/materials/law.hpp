#pragma once
/// Constitutive-law interface (method.md §3) and the registry that creates laws by name.
/// A law is called once per batch of points (a grain), never per point through a virtual call.
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
  /// Small-strain P-wave modulus M = lambda + 2 mu [Pa], for wave-speed estimates and scaling.
  virtual double wave_modulus() const = 0;
  /// Small-strain shear modulus mu [Pa].
  virtual double shear_modulus() const = 0;
};

/// A documented law parameter.
struct ParamSpec {
  std::string name;         ///< key in the [[materials]] table
  std::string unit;         ///< SI unit, e.g. "Pa"
  std::string description;  ///< one line
  double min = 0.0;         ///< smallest allowed value (inclusive)
  double max = 1e300;       ///< largest allowed value (inclusive)
};

/// Registry entry: a law's name, description and parameters (all required).
struct LawInfo {
  std::string name;               ///< registry name, e.g. "neo_hookean"
  std::string description;        ///< one line, with the equation it implements
  std::vector<ParamSpec> params;  ///< its parameters
};

/// All registered laws, in documentation order.
const std::vector<LawInfo>& law_registry();

/// Creates law `name` with `params` (validated against the registry; throws InputError).
template <int Dim>
std::unique_ptr<Law<Dim>> make_law(const std::string& name,
                                   const std::map<std::string, double>& params);

}  // namespace mpmcd::materials
