// Scratch folders and whole-file reads for the tests that run mpmcd or write files.
#pragma once
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

namespace mpmcd::test_support {

// The scratch folders this test program made, removed after its last test when every test passed
// (a suite run leaves nothing in the temporary folder); kept, and listed, when a test failed or
// MPMCD_KEEP_TEST_FILES is set, so that a failure can be looked at.
class ScratchFolders : public ::testing::Environment {
 public:
  void add(const std::filesystem::path& p) {
    for (const auto& q : folders_)
      if (q == p) return;
    folders_.push_back(p);
  }
  void TearDown() override {
    if (folders_.empty()) return;
    if (std::getenv("MPMCD_KEEP_TEST_FILES") != nullptr ||
        !::testing::UnitTest::GetInstance()->Passed()) {
      std::printf("scratch folders kept (a test failed or MPMCD_KEEP_TEST_FILES is set):\n");
      for (const auto& p : folders_) std::printf("  %s\n", p.string().c_str());
      return;
    }
    for (const auto& p : folders_) {
      std::error_code ec;  // a folder a test removed itself is not an error
      std::filesystem::remove_all(p, ec);
    }
  }

 private:
  std::vector<std::filesystem::path> folders_;
};

// The program's one registry, registered with GoogleTest before main runs (GoogleTest owns it).
inline ScratchFolders* const scratch_folders =
    static_cast<ScratchFolders*>(::testing::AddGlobalTestEnvironment(new ScratchFolders));

// <tmp>/mpmcd_<name>_<pid>, not created: the pid keeps concurrent test runs (other build trees on
// the machine) apart. Removed at the end of the program as scratch_folders says.
inline std::filesystem::path scratch_path(const std::string& name) {
  const std::filesystem::path p =
      std::filesystem::temp_directory_path() / ("mpmcd_" + name + "_" + std::to_string(getpid()));
  scratch_folders->add(p);
  return p;
}

// A fresh, empty folder <tmp>/mpmcd_<prefix>_<name>_<pid> (scratch_path).
inline std::filesystem::path scratch_dir(const std::string& prefix, const std::string& name) {
  const std::filesystem::path p = scratch_path(prefix + "_" + name);
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
