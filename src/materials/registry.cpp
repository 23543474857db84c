#include <fmt/format.h>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/materials/law.hpp"
#include "mpmcd/materials/laws.hpp"

namespace mpmcd::materials {

const std::vector<LawInfo>& law_registry() {
  static const std::vector<LawInfo> registry = {
      {"neo_hookean",
       "compressible Neo-Hookean, S = (lambda ln J - mu) C^-1 + mu I (paper eq. 8)",
       {{"lambda", "Pa", "first Lame coefficient", 0.0, 1e300},
        {"mu", "Pa", "shear modulus (second Lame coefficient), > 0", 1e-300, 1e300}}},
      {"saint_venant_kirchhoff",
       "Saint Venant-Kirchhoff, S = lambda tr(E) I + 2 mu E, E = (C - I)/2",
       {{"lambda", "Pa", "first Lame coefficient", 0.0, 1e300},
        {"mu", "Pa", "shear modulus, > 0", 1e-300, 1e300}}},
      {"linear_elastic",
       "small-strain linear elasticity, sigma = lambda tr(eps) I + 2 mu eps, eps = sym(F) - I",
       {{"lambda", "Pa", "first Lame coefficient", 0.0, 1e300},
        {"mu", "Pa", "shear modulus, > 0", 1e-300, 1e300}}},
  };
  return registry;
}

namespace {
const LawInfo& find_law(const std::string& name) {
  for (const auto& info : law_registry())
    if (info.name == name) return info;
  std::string known;
  for (const auto& info : law_registry()) known += (known.empty() ? "" : ", ") + info.name;
  throw InputError("", 0, "law", fmt::format("unknown law '{}', expected one of: {}", name, known));
}

double param(const LawInfo& info, const std::map<std::string, double>& params,
             const std::string& key) {
  auto it = params.find(key);
  if (it == params.end())
    throw InputError("", 0, key, fmt::format("law '{}' needs parameter '{}'", info.name, key));
  return it->second;
}
}  // namespace

template <int Dim>
std::unique_ptr<Law<Dim>> make_law(const std::string& name,
                                   const std::map<std::string, double>& params) {
  const LawInfo& info = find_law(name);
  for (const auto& [key, value] : params) {
    const ParamSpec* spec = nullptr;
    for (const auto& p : info.params)
      if (p.name == key) spec = &p;
    if (!spec)
      throw InputError("", 0, key, fmt::format("law '{}' has no parameter '{}'", name, key));
    if (!(value >= spec->min && value <= spec->max))
      throw InputError("", 0, key,
                       fmt::format("expected a value in [{}, {}] {}, got {}", spec->min, spec->max,
                                   spec->unit, value));
  }
  const double lambda = param(info, params, "lambda");
  const double mu = param(info, params, "mu");
  if (name == "neo_hookean") return std::make_unique<NeoHookean<Dim>>(lambda, mu);
  if (name == "saint_venant_kirchhoff")
    return std::make_unique<SaintVenantKirchhoff<Dim>>(lambda, mu);
  return std::make_unique<LinearElastic<Dim>>(lambda, mu);
}

template std::unique_ptr<Law<2>> make_law<2>(const std::string&,
                                             const std::map<std::string, double>&);
template std::unique_ptr<Law<3>> make_law<3>(const std::string&,
                                             const std::map<std::string, double>&);

}  // namespace mpmcd::materials
