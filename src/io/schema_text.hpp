#pragma once
// Text helpers shared by the schema, its reader and its Markdown renderer (private to src/io/).
#include <string>
#include <string_view>
#include <vector>

#include "mpmcd/io/schema.hpp"

namespace mpmcd::io::text {

/// The items separated by `sep`.
std::string join(const std::vector<std::string>& items, std::string_view sep);
/// `s` in double quotes, escaped, shortened to 60 characters ("..." after).
std::string quoted(std::string_view s);
/// " [unit]" of a key, "" if it has none.
std::string unit_suffix(const KeySpec& k);
/// True if `v` satisfies the bounds of key `k`.
bool in_range(const KeySpec& k, double v);
/// "> 0", ">= 1", "< 1", "[0.5, 1]", "(0, 1)", "" for the numeric bounds of `k`.
std::string bounds_text(const KeySpec& k);
/// " in [0.5, 1]", " > 0", "" (the bounds as a phrase after a type).
std::string bounds_phrase(const KeySpec& k);

}  // namespace mpmcd::io::text
