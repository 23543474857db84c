// docs/input.md must be the text generated from the schema (never hand-synced).
// To regenerate it, run from the repository root:
//   MPMCD_WRITE_INPUT_REFERENCE=docs/input.md <build>/tests/test_unit_io
//       --gtest_filter=InputReference.DocsMatchTheSchema
// (later: `mpmcd list input > docs/input.md`).
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "mpmcd/io/load_config.hpp"
#include "mpmcd/io/schema.hpp"
#include "mpmcd/materials/law.hpp"

TEST(InputReference, DocsMatchTheSchema) {
  const std::string generated = mpmcd::io::input_reference_markdown();
  if (const char* out = std::getenv("MPMCD_WRITE_INPUT_REFERENCE")) {
    std::ofstream(out, std::ios::binary) << generated;
    GTEST_SKIP() << "wrote the input reference to " << out;
  }
  const std::string path = std::string(MPMCD_SOURCE_DIR) + "/docs/input.md";
  std::ifstream in(path, std::ios::binary);
  ASSERT_TRUE(in) << "cannot read " << path;
  std::stringstream committed;
  committed << in.rdbuf();
  EXPECT_TRUE(committed.str() == generated)
      << "docs/input.md differs from the schema in src/io/config.cpp. Regenerate it from the "
         "repository root with:\n  MPMCD_WRITE_INPUT_REFERENCE=docs/input.md "
         "<build>/tests/test_unit_io --gtest_filter=InputReference.DocsMatchTheSchema";
}

TEST(InputReference, DocumentsEveryTableKeyAndLaw) {
  const std::string md = mpmcd::io::input_reference_markdown();
  const auto& schema = mpmcd::io::config_schema();
  for (const auto& t : schema.tables) {
    if (!t.header.empty()) {
      EXPECT_NE(md.find("## `" + t.header + "`"), std::string::npos);
    }
    for (const auto& k : t.keys) {
      const std::string path = t.path.empty() ? k.name : t.path + "." + k.name;
      EXPECT_NE(md.find("| `" + path + "` |"), std::string::npos) << path;
      EXPECT_FALSE(k.description.empty()) << path;
      EXPECT_TRUE(k.required || !k.default_text.empty() || !k.note.empty())
          << path << ": an optional key documents its default or when it is used";
      if (k.type == mpmcd::io::ValueType::kTable || k.type == mpmcd::io::ValueType::kTableArray) {
        EXPECT_NO_THROW((void)schema.table(k.table)) << path;
      }
    }
  }
  for (const auto& law : mpmcd::materials::law_registry()) {
    EXPECT_NE(md.find("### `" + law.name + "`"), std::string::npos) << law.name;
    for (const auto& p : law.params) {
      EXPECT_NE(md.find("| `" + p.name + "` |"), std::string::npos) << law.name << "." << p.name;
    }
  }
}

TEST(InputReference, EveryKeyIsBoundToTheMemberItFills) {
  // One declaration per key: the schema binds each key to its member of io::Config (only the
  // law parameters, added per material from the registry, are read by name).
  const auto& schema = mpmcd::io::config_schema();
  std::size_t keys = 0;
  for (const auto& t : schema.tables)
    for (const auto& k : t.keys) {
      const std::string path = t.path.empty() ? k.name : t.path + "." + k.name;
      EXPECT_NE(k.binding, nullptr) << path << " is not bound to a member";
      ++keys;
    }
  EXPECT_GE(keys, 89u);
  EXPECT_EQ(schema.table("time").find(&mpmcd::io::TimeSection::dt_min)->name, "dt_min");
  EXPECT_EQ(schema.table("").find(&mpmcd::io::Config::boundaries)->name, "boundary");
  EXPECT_EQ(schema.table("").find(&mpmcd::io::Config::boundaries)->table, "boundary[]");
}
