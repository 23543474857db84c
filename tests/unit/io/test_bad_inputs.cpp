// Every malformed input in bad_inputs/ must be refused with an InputError whose message contains
// the fragment listed for it in bad_inputs/expected.txt (file:line: key '...': expectation).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/io/load_config.hpp"

namespace {

const std::filesystem::path kDir = std::filesystem::path(MPMCD_TEST_DIR) / "bad_inputs";

/// file name -> message fragment, from expected.txt ("name.toml | fragment", '#' comments).
std::map<std::string, std::string> read_manifest() {
  std::map<std::string, std::string> out;
  std::ifstream in(kDir / "expected.txt");
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const auto bar = line.find(" | ");
    if (bar == std::string::npos) {
      ADD_FAILURE() << "malformed manifest line: " << line;
      continue;
    }
    out[line.substr(0, bar)] = line.substr(bar + 3);
  }
  return out;
}

}  // namespace

TEST(BadInputs, ManifestListsEveryFileOfTheCorpus) {
  const auto manifest = read_manifest();
  std::set<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(kDir))
    if (e.path().extension() == ".toml") files.insert(e.path().filename().string());
  for (const auto& f : files) EXPECT_TRUE(manifest.count(f)) << f << " is not in expected.txt";
  for (const auto& [f, frag] : manifest) EXPECT_TRUE(files.count(f)) << f << " does not exist";
  EXPECT_GE(files.size(), 30u);
}

TEST(BadInputs, EachIsRefusedWithItsMessage) {
  const auto manifest = read_manifest();
  ASSERT_FALSE(manifest.empty());
  for (const auto& [file, fragment] : manifest) {
    const std::string path = (kDir / file).string();
    try {
      (void)mpmcd::io::load_config(path);
      ADD_FAILURE() << file << ": loaded without error, expected: " << fragment;
    } catch (const mpmcd::InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(fragment), std::string::npos)
          << file << ":\n  message:  " << what << "\n  expected: " << fragment;
      EXPECT_EQ(what.rfind(path, 0), 0u) << file << ": message does not start with the path";
    } catch (const std::exception& e) {
      ADD_FAILURE() << file << ": not an InputError: " << e.what();
    }
  }
}

TEST(BadInputs, UnreadablePathsAreInputErrors) {
  using mpmcd::io::load_config;
  try {
    (void)load_config((kDir / "no_such_file.toml").string());
    FAIL() << "no error";
  } catch (const mpmcd::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no such file"), std::string::npos) << e.what();
  }
  try {
    (void)load_config(kDir.string());
    FAIL() << "no error";
  } catch (const mpmcd::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("it is a directory"), std::string::npos) << e.what();
  }
  try {
    (void)load_config("/dev/zero");  // never ends: must be refused before reading
    FAIL() << "no error";
  } catch (const mpmcd::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
  }
}
