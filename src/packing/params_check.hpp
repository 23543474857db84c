#pragma once
// Private to the packing module: range checks shared by generate_packing and the TOML loader.
#include <optional>
#include <string>

#include "mpmcd/packing/packing.hpp"

namespace mpmcd::packing::detail {

/// The first problem found in `params`: the offending field (TOML key under [packing]) and what
/// was expected. Empty when the parameters are usable.
struct ParamProblem {
  std::string key;          ///< field / key name, e.g. "target_phi" or "diameters"
  std::string expectation;  ///< what was expected, with the value found
};
std::optional<ParamProblem> check_params(const PackingParams& params);

/// Largest number of DEM steps a stage may be given [-].
inline constexpr std::int64_t kMaxSteps = 1'000'000'000;

}  // namespace mpmcd::packing::detail
