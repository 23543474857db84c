// CSV packing files and TOML packing inputs: round trip, foreign files, malformed content.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "../../support/scratch.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/packing/input.hpp"
#include "mpmcd/packing/overlap.hpp"
#include "mpmcd/packing/packing.hpp"

using namespace mpmcd::packing;
namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) {
  const auto dir = mpmcd::test_support::scratch_path("test_packing");
  fs::create_directories(dir);
  return dir / name;
}

std::string bad(const std::string& name) {
  return std::string(MPMCD_TEST_DIR) + "/bad/" + name;
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

struct BadCase {
  const char* file;     // under tests/unit/packing/bad/
  std::int64_t line;    // line the error must name (0: none)
  const char* message;  // fragment the message must contain
};

template <class Read>
void expect_rejected(const BadCase& c, Read read) {
  SCOPED_TRACE(c.file);
  try {
    read(bad(c.file));
    ADD_FAILURE() << c.file << ": accepted, expected InputError containing '" << c.message << "'";
  } catch (const mpmcd::InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(c.message), std::string::npos) << what;
    EXPECT_NE(what.find(c.file), std::string::npos) << "message must name the file: " << what;
    EXPECT_EQ(e.line(), c.line) << what;
    if (c.line > 0) {
      EXPECT_NE(what.find(":" + std::to_string(c.line) + ":"), std::string::npos) << what;
    }
  }
}

}  // namespace

TEST(PackingFile, WriteReadRoundTripIsExact) {
  Packing pk;
  pk.xmin = -0.1;
  pk.ymin = 1.0 / 3.0;
  pk.xmax = 0.2;
  pk.ymax = 0.7;
  pk.seed = 18446744073709551615ull;
  pk.disks = {{0, 0.1 / 3.0, 0.5, 1e-3 / 7.0}, {5, -0.05, 0.6, 2.0 / 3.0 * 1e-3}};
  const auto path = scratch("roundtrip.csv").string();
  write_packing_csv(pk, path);
  const Packing back = read_packing_csv(path);
  EXPECT_EQ(back.xmin, pk.xmin);
  EXPECT_EQ(back.ymin, pk.ymin);
  EXPECT_EQ(back.xmax, pk.xmax);
  EXPECT_EQ(back.ymax, pk.ymax);
  EXPECT_EQ(back.seed, pk.seed);
  EXPECT_FALSE(back.periodic);
  ASSERT_EQ(back.disks.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(back.disks[i].id, pk.disks[i].id);
    EXPECT_EQ(back.disks[i].x, pk.disks[i].x);
    EXPECT_EQ(back.disks[i].y, pk.disks[i].y);
    EXPECT_EQ(back.disks[i].radius, pk.disks[i].radius);
  }
}

TEST(PackingFile, ForeignFileWithoutBoxGetsTheBoundingBox) {
  // Columns in another order, an extra column, CRLF line ends, blank lines, no header comments.
  const auto path = scratch("foreign.csv");
  write_text(
      path,
      "radius, y, colour, id, x\r\n\r\n0.5e-3,1e-3,red,10,1e-3\r\n+1e-3,3e-3,blue,2,4e-3\r\n");
  const Packing pk = read_packing_csv(path.string());
  ASSERT_EQ(pk.disks.size(), 2u);
  EXPECT_EQ(pk.disks[0].id, 10);
  EXPECT_EQ(pk.disks[1].radius, 1e-3);
  EXPECT_DOUBLE_EQ(pk.xmin, 0.5e-3);
  EXPECT_DOUBLE_EQ(pk.ymin, 0.5e-3);
  EXPECT_DOUBLE_EQ(pk.xmax, 5e-3);
  EXPECT_DOUBLE_EQ(pk.ymax, 4e-3);
  EXPECT_EQ(pk.seed, 0u);
}

TEST(PackingFile, VtuIsWritten) {
  Packing pk;
  pk.xmax = pk.ymax = 1.0;
  pk.disks = {{0, 0.5, 0.5, 0.1}, {1, 0.2, 0.2, 0.1}};
  const auto path = scratch("p.vtu");
  write_packing_vtu(pk, path.string());
  std::ifstream in(path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(text.find("NumberOfPoints=\"2\""), std::string::npos);
  EXPECT_NE(text.find("Name=\"radius\""), std::string::npos);
  EXPECT_NE(text.find("Name=\"diameter\""), std::string::npos);
  EXPECT_NE(text.find("Name=\"id\""), std::string::npos);
}

TEST(PackingFile, MalformedFilesAreRejectedWithFileAndLine) {
  const BadCase cases[] = {
      {"nonnumeric.csv", 6, "key 'x': a number, got 'abc'"},
      {"wrong_field_count.csv", 4, "4 comma-separated fields as in the header, got 3"},
      {"negative_radius.csv", 3, "a radius > 0"},
      {"zero_radius.csv", 4, "a radius > 0"},
      {"nan.csv", 3, "key 'x': a finite number"},
      {"inf.csv", 4, "key 'y': a finite number"},
      {"duplicate_id.csv", 5, "id 7 already on line 3"},
      {"empty.csv", 0, "column header"},
      {"comments_only.csv", 2, "column header"},
      {"binary.csv", 2, "binary"},
      {"disk_outside.csv", 4, "it is outside"},
      {"bad_header.csv", 2, "column header 'id,x,y,radius'"},
      {"bad_box.csv", 1, "key 'box'"},
      {"no_rows.csv", 2, "at least one disk"},
      {"non_integer_id.csv", 3, "key 'id': an integer, got '1.5'"},
      {"does_not_exist.csv", 0, "cannot read"},
      {"duplicated_disk.csv", 6,
       "disk id 4 to overlap no other disk (touching is fine: up to 0.001 of the smaller "
       "diameter), but it overlaps disk id 2 of line 4 by 0.001 m = 1 of the smaller diameter"},
  };
  for (const auto& c : cases) expect_rejected(c, [](const std::string& p) { read_packing_csv(p); });
}

TEST(PackingInputFile, MalformedInputsAreRejectedWithFileLineAndKey) {
  const BadCase cases[] = {
      {"unknown_key.toml", 7, "key 'packing.colour': unknown key"},
      {"wrong_type.toml", 2, "key 'packing.count': an integer, got a string"},
      {"missing_target_phi.toml", 1, "target_phi"},
      {"phi_out_of_range.toml", 6, "key 'packing.target_phi': a number in (0, 0.9], got 0.95"},
      {"huge_count.toml", 2, "key 'packing.count': an integer in [1, 1000000]"},
      {"syntax_error.toml", 3, "valid TOML"},
      {"box_and_aspect.toml", 1, "exactly one of 'box'"},
      {"bad_method.toml", 7, "key 'packing.method': one of \"grow\", \"walls\", \"jam\""},
      {"negative_seed.toml", 7, "key 'packing.seed': an integer >= 0, got -3"},
      {"nan_diameter.toml", 2, "key 'packing.diameters': a finite number (entry 2)"},
      {"unknown_table.toml", 8, "key 'grid': unknown table"},
      {"binary.toml", 2, "valid TOML"},
      {"dmax_below_dmin.toml", 4, "key 'packing.diameter_max': a finite number >= diameter_min"},
      {"float_count.toml", 2, "key 'packing.count': an integer, got a float"},
      {"box_too_short.toml", 5, "key 'packing.box': an array of 4 numbers, got 3"},
      {"bad_output_name.toml", 9, "key 'output.name': a plain file name"},
      {"does_not_exist.toml", 0, "does not exist"},
  };
  for (const auto& c : cases)
    expect_rejected(c, [](const std::string& p) { load_packing_input(p); });
}

TEST(PackingInputFile, ExampleLoads) {
  const auto in = load_packing_input(std::string(MPMCD_SOURCE_DIR) + "/examples/packing/pack.toml");
  EXPECT_EQ(in.params.count, 300);
  EXPECT_EQ(in.params.method, PackingMethod::kGrow);
  EXPECT_DOUBLE_EQ(in.params.target_phi, 0.78);
  EXPECT_FALSE(in.params.box.has_value());
}

// Issue 17: disks may touch (within kOverlapTolerance of the smaller diameter), not overlap.
TEST(PackingFile, TouchingDisksPassOverlappingOnesAreRefusedWithBothLines) {
  const auto text = [](double gap) {
    return fmt::format("id,x,y,radius\n0,0.0,0.0,0.5e-3\n1,{:.17g},0.0,0.5e-3\n", 1e-3 + gap);
  };
  EXPECT_EQ(parse_packing_csv(text(0.0), "p.csv").disks.size(), 2u);      // touching
  EXPECT_EQ(parse_packing_csv(text(-0.9e-6), "p.csv").disks.size(), 2u);  // 9e-4 d
  try {
    parse_packing_csv(text(-1.1e-6), "p.csv");  // 1.1e-3 d
    ADD_FAILURE() << "an overlap of 1.1e-3 d was accepted";
  } catch (const mpmcd::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("p.csv:3: disk id 1 to overlap no other disk"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("overlaps disk id 0 of line 2 by 1.1e-06 m"),
              std::string::npos)
        << e.what();
  }
}

TEST(Overlap, DisksAndRectanglesInCellsAndAgainstEveryOutline) {
  // 2000 disks on a lattice, touching their neighbours: no overlap.
  std::vector<Outline> o;
  for (int i = 0; i < 2000; ++i) o.push_back({(i % 50) * 2.0, (i / 50) * 2.0, 0, 0, 1.0});
  EXPECT_FALSE(find_overlap(o, kOverlapTolerance));
  // A rectangle over the lattice (compared with every disk) overlaps the first disk it reaches.
  o.push_back({-10.0, -10.0, 200.0, -0.5, 0.0});
  auto hit = find_overlap(o, kOverlapTolerance);
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->first, 0u);
  EXPECT_EQ(hit->second, 2000u);
  EXPECT_DOUBLE_EQ(hit->depth, 0.5);
  o.pop_back();
  // A disk shifted onto its neighbour: found with the lowest later index.
  o[1234].x0 -= 0.5;
  hit = find_overlap(o, kOverlapTolerance);
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->first, 1233u);
  EXPECT_EQ(hit->second, 1234u);
  EXPECT_DOUBLE_EQ(hit->size, 2.0);
  // Rectangles: sharing a side is touching; overlapping by 0.1 is not.
  EXPECT_FALSE(find_overlap({{0, 0, 1, 1, 0}, {1, 0, 2, 1, 0}}, kOverlapTolerance));
  hit = find_overlap({{0, 0, 1, 1, 0}, {0.9, 0.5, 2, 1, 0}}, kOverlapTolerance);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->depth, 0.1, 1e-12);
  // A disk whose centre is inside a rectangle.
  hit = find_overlap({{0, 0, 1, 1, 0}, {0.5, 0.9, 0, 0, 0.05}}, kOverlapTolerance);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->depth, 0.15, 1e-12);
}
