#include <fmt/format.h>

#include <stdexcept>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/materials/law.hpp"
#include "mpmcd/materials/linear_elastic.hpp"
#include "mpmcd/materials/neo_hookean.hpp"
#include "mpmcd/materials/saint_venant_kirchhoff.hpp"

namespace mpmcd::materials {

namespace {

// The registry: the built-in laws, one line each, in documentation order (docs/input.md).
std::vector<LawInfo>& registry() {
  static std::vector<LawInfo> laws = {
      neo_hookean_law(),
      saint_venant_kirchhoff_law(),
      linear_elastic_law(),
  };
  return laws;
}

const LawInfo& find_law(const std::string& name) {
  for (const auto& info : law_registry())
    if (info.name == name) return info;
  std::string known;
  for (const auto& info : law_registry()) known += (known.empty() ? "" : ", ") + info.name;
  throw InputError("", 0, "law", fmt::format("unknown law '{}', expected one of: {}", name, known));
}

// Throws InputError unless `params` are exactly the law's parameters, each in its range.
void check_params(const LawInfo& info, const LawParams& params) {
  for (const auto& [key, value] : params) {
    const ParamSpec* spec = nullptr;
    for (const auto& p : info.params)
      if (p.name == key) spec = &p;
    if (!spec)
      throw InputError("", 0, key, fmt::format("law '{}' has no parameter '{}'", info.name, key));
    if (!(value >= spec->min && value <= spec->max))
      throw InputError("", 0, key,
                       fmt::format("expected a value in [{}, {}] {}, got {}", spec->min, spec->max,
                                   spec->unit, value));
  }
  for (const auto& p : info.params)
    if (!params.contains(p.name))
      throw InputError("", 0, p.name,
                       fmt::format("law '{}' needs parameter '{}'", info.name, p.name));
}

}  // namespace

const std::vector<LawInfo>& law_registry() {
  return registry();
}

void register_law(LawInfo law) {
  if (!law.create_2d || !law.create_3d)
    throw std::invalid_argument(fmt::format("law '{}' has no factory", law.name));
  for (const auto& info : registry())
    if (info.name == law.name)
      throw std::invalid_argument(fmt::format("law '{}' is registered already", law.name));
  registry().push_back(std::move(law));
}

template <int Dim>
std::unique_ptr<Law<Dim>> make_law(const std::string& name, const LawParams& params) {
  const LawInfo& info = find_law(name);
  check_params(info, params);
  return info.factory<Dim>()(params);
}

template std::unique_ptr<Law<2>> make_law<2>(const std::string&, const LawParams&);
template std::unique_ptr<Law<3>> make_law<3>(const std::string&, const LawParams&);

}  // namespace mpmcd::materials
