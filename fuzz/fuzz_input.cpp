// Fuzz target: the TOML simulation input (io::parse_config). Only InputError may come out.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/io/load_config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    (void)mpmcd::io::parse_config(text, "/nonexistent/fuzz.toml");
  } catch (const mpmcd::InputError&) {
  }
  return 0;
}
