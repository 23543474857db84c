// The generic schema checker on a toy input (as a packing reader would use it).
#include <gtest/gtest.h>

#include <string>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/io/schema.hpp"

using mpmcd::io::CheckContext;
using mpmcd::io::KeySpec;
using mpmcd::io::Schema;
using mpmcd::io::TableReader;

namespace {

Schema toy_schema() {
  Schema s;
  s.title = "toy";
  s.tables.push_back({"", "", "root", {KeySpec::subtable("box", "box", "a box").require()}, ""});
  s.tables.push_back(
      {"box",
       "[box]",
       "a box",
       {KeySpec::numbers("size", "N", "m", "edge lengths").require().greater_than(0.0),
        KeySpec::integer("count", "", "how many").at_least(1).at_most(10).defaults("3"),
        KeySpec::string("kind", "what").one_of({"hard", "soft"}).defaults("\"hard\""),
        KeySpec::strings("tags", "labels").nonempty().distinct(),
        KeySpec::boolean("open", "open box").defaults("false")},
       ""});
  return s;
}

std::string error_of(const std::string& text, const CheckContext& ctx) {
  const Schema s = toy_schema();
  try {
    const toml::table root = toml::parse(text, std::string_view("toy.toml"));
    TableReader r(root, s.table(""), ctx, "", 0);
    TableReader box(*r.subtable("box"), s.table("box"), ctx, "box", 1);
  } catch (const mpmcd::InputError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST(Schema, NearestNameSuggestsOnlyCloseNames) {
  EXPECT_EQ(mpmcd::io::nearest_name("cel_size", {"cell_size", "origin"}), "cell_size");
  EXPECT_EQ(mpmcd::io::nearest_name("boundaries", {"boundary", "grains"}), "boundary");
  EXPECT_EQ(mpmcd::io::nearest_name("zzzzzz", {"cell_size", "origin"}), "");
  EXPECT_EQ(mpmcd::io::nearest_name("origin", {"origin"}), "");  // exact: nothing to suggest
}

TEST(Schema, ReaderChecksAndReadsAGenericTable) {
  const CheckContext ctx{"toy.toml", {{"N", 3}}};
  const Schema s = toy_schema();
  const toml::table root =
      toml::parse(std::string_view("[box]\nsize = [1, 2.5, 3]\nkind = \"soft\"\ntags = [\"a\"]\n"),
                  std::string_view("toy.toml"));
  TableReader box(*root["box"].as_table(), s.table("box"), ctx, "box", 1);
  std::vector<double> size;
  int count = 3;
  std::string kind = "hard";
  std::vector<std::string> tags;
  bool open = false;
  box.read("size", size);
  box.read("count", count);
  box.read("kind", kind);
  box.read("tags", tags);
  box.read("open", open);
  EXPECT_EQ(size, (std::vector<double>{1.0, 2.5, 3.0}));
  EXPECT_EQ(count, 3);  // absent: default kept
  EXPECT_EQ(kind, "soft");
  EXPECT_EQ(tags, (std::vector<std::string>{"a"}));
  EXPECT_FALSE(open);
  EXPECT_TRUE(box.has("size"));
  EXPECT_FALSE(box.has("count"));
  EXPECT_EQ(box.line("size"), 2);
  EXPECT_EQ(box.key_path("size"), "box.size");
}

TEST(Schema, ReaderErrors) {
  const CheckContext ctx{"toy.toml", {{"N", 2}}};
  EXPECT_EQ(error_of("", ctx), "toy.toml: key 'box': missing required table [box]");
  EXPECT_EQ(error_of("[box]\nsize = [1, 2]\ncont = 2\n", ctx),
            "toy.toml:3: key 'box.cont': unknown key, did you mean 'count'?");
  EXPECT_EQ(error_of("[box]\nsize = [1, 2, 3]\n", ctx),
            "toy.toml:2: key 'box.size': expected an array of 2 finite numbers, each > 0 [m], got "
            "3 entries");
  EXPECT_EQ(error_of("[box]\nsize = [1, 0]\n", ctx),
            "toy.toml:2: key 'box.size[1]': expected a finite number > 0 [m], got 0");
  EXPECT_EQ(error_of("[box]\nsize = [1, 2]\ncount = 11\n", ctx),
            "toy.toml:3: key 'box.count': expected an integer in [1, 10], got 11");
  EXPECT_EQ(error_of("[box]\nsize = [1, 2]\nkind = \"sofd\"\n", ctx),
            "toy.toml:3: key 'box.kind': expected one of hard, soft, got \"sofd\" (did you mean "
            "\"soft\"?)");
  EXPECT_EQ(error_of("[box]\nsize = [1, 2]\ntags = [\"a\", \"a\"]\n", ctx),
            "toy.toml:3: key 'box.tags[1]': duplicate entry \"a\" (expected a non-empty array of "
            "strings without duplicates)");
  EXPECT_EQ(error_of("[box]\nsize = [1, 2]\nopen = 1\n", ctx),
            "toy.toml:3: key 'box.open': expected a boolean (true or false), got the integer 1");
  EXPECT_EQ(error_of("[box]\n", ctx),
            "toy.toml:1: key 'box.size': missing required key (an array of 2 finite numbers, "
            "each > 0 [m])");
}

TEST(Schema, MarkdownHasOneRowPerKey) {
  const std::string md = mpmcd::io::schema_markdown(toy_schema());
  EXPECT_NE(md.find("# toy"), std::string::npos);
  EXPECT_NE(md.find("## `[box]`"), std::string::npos);
  EXPECT_NE(md.find("| `box.size` | array of numbers (N) | **required** | entries > 0 | m | edge "
                    "lengths |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| `box.count` | integer | `3` | [1, 10] | – | how many |"), std::string::npos)
      << md;
  EXPECT_EQ(mpmcd::io::markdown_cell("a|b\nc"), "a\\|b c");
}
