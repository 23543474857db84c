// Fuzz target: the checkpoint reader behind its checksum. The bytes are taken as the HDF5 part of
// a checkpoint and sealed with a valid header (size and FNV-1a), so libhdf5 and the dataset checks
// of checkpoint::read see every mutation. Only InputError may come out. A crash here inside
// libhdf5 is a file that passes our checksum, i.e. one corrupted and re-sealed on purpose.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

#include "mpmcd/checkpoint/checkpoint.hpp"
#include "mpmcd/core/errors.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/tmp/mpmcd_fuzz_sealed_" + std::to_string(getpid()) + ".h5";
  const std::string_view body(reinterpret_cast<const char*>(data), size);
  const std::string head = mpmcd::checkpoint::header_for(body);
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  std::fwrite(head.data(), 1, head.size(), f);
  std::fwrite(data, 1, size, f);
  std::fclose(f);
  try {
    (void)mpmcd::checkpoint::read(path);
  } catch (const mpmcd::InputError&) {
  }
  return 0;
}
