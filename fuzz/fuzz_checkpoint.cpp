// Fuzz target: the checkpoint reader (checkpoint::read) on arbitrary bytes written to a file.
// Only InputError may come out. The header checksum stops random bytes before libhdf5; seeds
// that are valid checkpoints exercise the header checks against mutations.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "mpmcd/checkpoint/checkpoint.hpp"
#include "mpmcd/core/errors.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/tmp/mpmcd_fuzz_checkpoint_" + std::to_string(getpid()) + ".h5";
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  std::fwrite(data, 1, size, f);
  std::fclose(f);
  try {
    (void)mpmcd::checkpoint::read(path);
  } catch (const mpmcd::InputError&) {
  }
  return 0;
}
