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

// ---------------------------------------------------------------------------------------------
// Keys bound to the members they fill

namespace {

struct Item {
  std::string label;
  double weight = 0.5;
};

struct Box {
  std::vector<double> size;
  int count = 3;
  std::string kind = "hard";
  std::vector<std::string> tags;
  bool open = false;
  std::int64_t serial = 0;
  Item lid;
  std::vector<Item> items;
};

struct Toy {
  Box box;
};

Schema bound_schema() {
  Schema s;
  s.title = "bound toy";
  s.tables.push_back(
      {"", "", "root", {KeySpec::subtable("box", &Toy::box, "a box").require()}, ""});
  s.add_table(
      &Toy::box, "a box",
      {KeySpec::numbers("size", &Box::size, "N", "m", "edge lengths").require(),
       KeySpec::integer("count", &Box::count, "", "how many").at_least(1).default_of_member(),
       KeySpec::string("kind", &Box::kind, "what").one_of({"hard", "soft"}).default_of_member(),
       KeySpec::strings("tags", &Box::tags, "labels").distinct(),
       KeySpec::boolean("open", &Box::open, "open box").default_of_member(),
       KeySpec::integer("serial", &Box::serial, "", "serial number").default_of_member(),
       KeySpec::subtable("lid", &Box::lid, "its lid").defaults("none"),
       KeySpec::table_array("items", &Box::items, "its content").defaults("none")});
  s.add_table(&Box::lid, "a lid",
              {KeySpec::string("label", &Item::label, "name").default_of_member(),
               KeySpec::number("weight", &Item::weight, "kg", "mass").default_of_member()});
  s.add_table(&Box::items, "an item",
              {KeySpec::string("label", &Item::label, "name").require(),
               KeySpec::number("weight", &Item::weight, "kg", "mass").default_of_member()});
  return s;
}

// A binding only compiles with a member of the key's C++ type.
template <class M>
concept BindsAsNumber = requires(M m) {
  KeySpec::number("n", m, "", "");
};
template <class M>
concept BindsAsInteger = requires(M m) {
  KeySpec::integer("n", m, "", "");
};
template <class M>
concept BindsAsString = requires(M m) {
  KeySpec::string("n", m, "");
};
template <class M>
concept BindsAsNumbers = requires(M m) {
  KeySpec::numbers("n", m, "", "", "");
};
static_assert(BindsAsNumber<double Item::*>);
static_assert(!BindsAsNumber<int Box::*>);
static_assert(!BindsAsNumber<std::string Box::*>);
static_assert(BindsAsInteger<int Box::*> && BindsAsInteger<std::int64_t Box::*>);
static_assert(!BindsAsInteger<double Item::*> && !BindsAsInteger<bool Box::*>);
static_assert(BindsAsString<std::string Box::*> && !BindsAsString<std::vector<std::string> Box::*>);
static_assert(BindsAsNumbers<std::vector<double> Box::*> && !BindsAsNumbers<double Item::*>);

}  // namespace

TEST(Schema, AddedTablesTakeTheirPathAndHeaderFromTheKey) {
  const Schema s = bound_schema();
  ASSERT_EQ(s.tables.size(), 4u);
  EXPECT_EQ(s.tables[1].path, "box");
  EXPECT_EQ(s.tables[1].header, "[box]");
  EXPECT_EQ(s.tables[2].path, "box.lid");
  EXPECT_EQ(s.tables[2].header, "[box.lid]");
  EXPECT_EQ(s.tables[3].path, "box.items[]");
  EXPECT_EQ(s.tables[3].header, "[[box.items]]");
  EXPECT_EQ(s.table("").find("box")->table, "box");
  EXPECT_EQ(s.table("box").find("items")->table, "box.items[]");
  // Documented defaults come from a default-constructed struct.
  EXPECT_EQ(s.table("box").find("count")->default_text, "3");
  EXPECT_EQ(s.table("box").find("kind")->default_text, "\"hard\"");
  EXPECT_EQ(s.table("box").find("open")->default_text, "false");
  EXPECT_EQ(s.table("box.lid").find("weight")->default_text, "0.5");
  EXPECT_EQ(s.table("box").find(&Box::kind), s.table("box").find("kind"));
  EXPECT_EQ(s.table("box").find(&Box::open), s.table("box").find("open"));
  EXPECT_EQ(s.table("box").find(&Item::weight), nullptr);
  Schema bad = bound_schema();
  EXPECT_THROW(bad.add_table(&Item::weight, "not a table", {}), std::logic_error);
  EXPECT_THROW((void)KeySpec::numbers("v", &Box::size, "", "", "").default_of_member(),
               std::logic_error);
}

TEST(Schema, FillAssignsTheBoundMembersThatArePresent) {
  const Schema s = bound_schema();
  CheckContext ctx{"toy.toml", {{"N", 2}}};
  ctx.schema = &s;
  const toml::table root = toml::parse(
      std::string_view("[box]\nsize = [1, 2.5]\nkind = \"soft\"\ntags = [\"a\", \"b\"]\nserial = "
                       "7\n[box.lid]\nlabel = \"top\"\n[[box.items]]\nlabel = \"x\"\nweight = 2\n"
                       "[[box.items]]\nlabel = \"y\"\n"),
      std::string_view("toy.toml"));
  const TableReader r(root, s.table(""), ctx, "", 0);
  Toy toy;
  const TableReader box = r.sub(&Toy::box);
  box.fill(toy.box);
  EXPECT_EQ(toy.box.size, (std::vector<double>{1.0, 2.5}));
  EXPECT_EQ(toy.box.count, 3);  // absent: default kept
  EXPECT_EQ(toy.box.kind, "soft");
  EXPECT_EQ(toy.box.tags, (std::vector<std::string>{"a", "b"}));
  EXPECT_FALSE(toy.box.open);
  EXPECT_EQ(toy.box.serial, 7);
  box.sub(&Box::lid).fill(toy.box.lid);
  EXPECT_EQ(toy.box.lid.label, "top");
  EXPECT_EQ(toy.box.lid.weight, 0.5);
  const auto tables = box.tables(&Box::items);
  ASSERT_EQ(tables.size(), 2u);
  for (std::size_t i = 0; i < tables.size(); ++i) {
    const TableReader item = box.element(&Box::items, i, *tables[i]);
    EXPECT_EQ(item.path(), "box.items[" + std::to_string(i) + "]");
    Item it;
    item.fill(it);
    toy.box.items.push_back(it);
  }
  EXPECT_EQ(toy.box.items[0].label, "x");
  EXPECT_EQ(toy.box.items[0].weight, 2.0);
  EXPECT_EQ(toy.box.items[1].weight, 0.5);
  // Keys are named by their members.
  EXPECT_EQ(box.name(&Box::kind), "kind");
  EXPECT_TRUE(box.has(&Box::kind));
  EXPECT_FALSE(box.has(&Box::count));
  EXPECT_EQ(box.line(&Box::kind), 3);
  EXPECT_EQ(box.line(&Box::count), box.line());
  try {
    box.fail(&Box::tags, "expected fewer tags");
    ADD_FAILURE() << "fail returned";
  } catch (const mpmcd::InputError& e) {
    EXPECT_STREQ(e.what(), "toy.toml:4: key 'box.tags': expected fewer tags");
  }
  // An absent sub-table reads as an empty one; a member of another struct is a programming error.
  const toml::table no_lid = toml::parse(std::string_view("[box]\nsize = [1, 2]\n"));
  const TableReader r2(no_lid, s.table(""), ctx, "", 0);
  Item lid;
  r2.sub(&Toy::box).sub(&Box::lid).fill(lid);
  EXPECT_EQ(lid.label, "");
  EXPECT_THROW((void)box.name(&Item::label), std::logic_error);
  Item wrong;
  EXPECT_THROW(box.fill(wrong), std::logic_error);
}
