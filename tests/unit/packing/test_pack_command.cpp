// The `mpmcd pack` entry point: input file to CSV + VTU + summary line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "../../support/scratch.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/packing/pack_command.hpp"
#include "mpmcd/packing/packing.hpp"

namespace fs = std::filesystem;
using namespace mpmcd::packing;

TEST(PackCommand, WritesCsvVtuAndSummary) {
  const auto dir = mpmcd::test_support::scratch_path("test_pack");
  fs::create_directories(dir);
  const auto input = dir / "pack.toml";
  const auto folder = dir / "out";
  std::ofstream(input) << "[packing]\ncount = 50\ndiameter_min = 0.8e-3\ndiameter_max = 1.2e-3\n"
                          "box = [0.0, 0.0, 0.006, 0.005]\ntarget_phi = 0.75\nseed = 5\n"
                          "[output]\nfolder = \""
                       << folder.string() << "\"\nname = \"p\"\n";
  testing::internal::CaptureStdout();
  const int rc = pack_command(input.string(), true);
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_EQ(rc, 0);
  EXPECT_NE(out.find("packing: 50 grains, phi = 0.75"), std::string::npos) << out;
  EXPECT_NE(out.find("max overlap"), std::string::npos) << out;
  ASSERT_TRUE(fs::exists(folder / "p.vtu"));
  const Packing pk = read_packing_csv((folder / "p.csv").string());
  EXPECT_EQ(pk.disks.size(), 50u);
  EXPECT_EQ(pk.seed, 5u);
  EXPECT_EQ(pk.xmax, 0.006);
  EXPECT_NEAR(packing_fraction(pk), 0.75, 1e-9);
  fs::remove_all(dir);
}

TEST(PackCommand, BadInputThrowsInputError) {
  EXPECT_THROW(pack_command(std::string(MPMCD_TEST_DIR) + "/bad/unknown_key.toml", true),
               mpmcd::InputError);
}
