// Fuzz target: the CSV packing file reader (packing::parse_packing_csv). Only InputError may
// come out.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/packing/packing.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    (void)mpmcd::packing::parse_packing_csv(text, "fuzz.csv");
  } catch (const mpmcd::InputError&) {
  }
  return 0;
}
