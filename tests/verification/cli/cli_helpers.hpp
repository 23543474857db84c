// What the command-line tests (test_cli*.cpp) share: running mpmcd (Result, run), the example
// they run, their scratch folders, a one-grain input written from its grain and time sections, a
// folder's file names. A test file takes them all with `using namespace mpmcd::test_support::cli`.
#pragma once
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "../../support/cli_runner.hpp"
#include "../../support/scratch.hpp"

namespace mpmcd::test_support::cli {

namespace fs = std::filesystem;
using test_support::Result;
using test_support::run;

// The squeezed-disk example's input.
inline std::string example() {
  return std::string(MPMCD_SOURCE_DIR) + "/examples/squeezed_disk/squeezed_disk.toml";
}

// A fresh scratch folder of the command-line tests.
inline std::filesystem::path scratch(const std::string& name) {
  return scratch_dir("cli", name);
}

// Writes an input whose only grain is given by `grain` and time section by `time`.
inline std::filesystem::path write_input(const std::filesystem::path& dir, const std::string& grain,
                                         const std::string& time) {
  const std::filesystem::path p = dir / "case.toml";
  std::ofstream(p) << "[grid]\norigin = [0.0, 0.0]\nextent = [0.02, 0.02]\ncell_size = 0.001\n"
                      "[[materials]]\nname = \"gel\"\nlaw = \"neo_hookean\"\ndensity = 990.0\n"
                      "lambda = 3e6\nmu = 1.5e6\n"
                   << grain << time << "[output]\nfolder = \"out\"\n";
  return p;
}

// The names of the files in dir, sorted.
inline std::vector<std::string> names_in(const std::filesystem::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace mpmcd::test_support::cli
