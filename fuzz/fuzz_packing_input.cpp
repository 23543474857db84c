// Fuzz target: the TOML packing input (packing::parse_packing_input). Only InputError may come
// out; the packing is validated, not generated.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/packing/input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    (void)mpmcd::packing::parse_packing_input(text, "fuzz_packing.toml");
  } catch (const mpmcd::InputError&) {
  }
  return 0;
}
