// The contact-law registry (include/mpmcd/contact/law.hpp): the built-in laws, one line each, the
// laws a test or a tool registers, and the look-up by name.
#include "mpmcd/contact/law.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "mpmcd/core/errors.hpp"

namespace mpmcd::contact {

namespace {

// The registry: the built-in laws, one line each, in documentation order (docs/input.md).
std::vector<ContactLaw>& registry() {
  static std::vector<ContactLaw> laws = {
      coulomb_law(),
  };
  return laws;
}

}  // namespace

bool ContactLaw::reads(const std::string& param) const {
  return std::find(params.begin(), params.end(), param) != params.end();
}

const std::vector<ContactLaw>& contact_law_registry() {
  return registry();
}

std::vector<std::string> contact_law_names() {
  std::vector<std::string> names;
  for (const auto& law : registry()) names.push_back(law.name);
  return names;
}

const ContactLaw& find_contact_law(const std::string& name) {
  for (const auto& law : registry())
    if (law.name == name) return law;
  std::string known;
  for (const auto& law : registry()) known += (known.empty() ? "" : ", ") + law.name;
  throw InputError("", 0, "contact.law",
                   fmt::format("unknown contact law '{}', expected one of: {}", name, known));
}

void register_contact_law(ContactLaw law) {
  if (!law.local_2d || !law.local_3d)
    throw std::invalid_argument(fmt::format("contact law '{}' has no local solver", law.name));
  for (const auto& known : registry())
    if (known.name == law.name)
      throw std::invalid_argument(fmt::format("contact law '{}' is registered already", law.name));
  registry().push_back(std::move(law));
}

}  // namespace mpmcd::contact
