// Scratch folders and whole-file reads for the tests that run mpmcd or write files.
#pragma once
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace mpmcd::test_support {

// A fresh, empty folder <tmp>/mpmcd_<prefix>_<name>_<pid>: the pid keeps concurrent test runs
// (other build trees on the machine) apart.
inline std::filesystem::path scratch_dir(const std::string& prefix, const std::string& name) {
  const std::filesystem::path p = std::filesystem::temp_directory_path() /
                                  ("mpmcd_" + prefix + "_" + name + "_" + std::to_string(getpid()));
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p;
}

// The bytes of file p ("" if it cannot be read).
inline std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace mpmcd::test_support
