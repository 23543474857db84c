#pragma once
// The keys of a [[materials]] table that come from the law registry (private to src/io/): they
// are checked and read by name, since the law decides which parameters the table holds.
#include <string>
#include <vector>

#include "mpmcd/io/schema.hpp"
#include "mpmcd/materials/law.hpp"

namespace mpmcd::io {

/// KeySpecs of a law's parameters (all required, SI units), from the materials registry.
std::vector<KeySpec> law_keys(const materials::LawInfo& law);

/// Names of the laws of the materials registry, in registry order.
std::vector<std::string> law_names();

}  // namespace mpmcd::io
