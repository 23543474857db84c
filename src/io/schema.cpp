// The generic input schema: KeySpec builders, table look-ups, and the human text of keys
// (types, ranges, node descriptions) used by the reader's messages and the Markdown reference.
#include "mpmcd/io/schema.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "schema_text.hpp"

namespace mpmcd::io {

// ---------------------------------------------------------------------------------------------
// KeySpec builders

namespace {
KeySpec make_key(std::string name, ValueType type, std::string unit, std::string description) {
  KeySpec k;
  k.name = std::move(name);
  k.type = type;
  k.unit = std::move(unit);
  k.description = std::move(description);
  return k;
}
}  // namespace

KeySpec KeySpec::number(std::string name, std::string unit, std::string description) {
  return make_key(std::move(name), ValueType::kNumber, std::move(unit), std::move(description));
}
KeySpec KeySpec::integer(std::string name, std::string unit, std::string description) {
  return make_key(std::move(name), ValueType::kInteger, std::move(unit), std::move(description));
}
KeySpec KeySpec::string(std::string name, std::string description) {
  return make_key(std::move(name), ValueType::kString, "", std::move(description));
}
KeySpec KeySpec::boolean(std::string name, std::string description) {
  return make_key(std::move(name), ValueType::kBool, "", std::move(description));
}
KeySpec KeySpec::numbers(std::string name, std::string length, std::string unit,
                         std::string description) {
  KeySpec k =
      make_key(std::move(name), ValueType::kNumberArray, std::move(unit), std::move(description));
  k.length = std::move(length);
  return k;
}
KeySpec KeySpec::strings(std::string name, std::string description) {
  return make_key(std::move(name), ValueType::kStringArray, "", std::move(description));
}
KeySpec KeySpec::subtable(std::string name, std::string table_path, std::string description) {
  KeySpec k = make_key(std::move(name), ValueType::kTable, "", std::move(description));
  k.table = std::move(table_path);
  return k;
}
KeySpec KeySpec::table_array(std::string name, std::string table_path, std::string description) {
  KeySpec k = make_key(std::move(name), ValueType::kTableArray, "", std::move(description));
  k.table = std::move(table_path);
  return k;
}

KeySpec KeySpec::bound(std::string name, ValueType type, std::string length, std::string unit,
                       std::string description, std::shared_ptr<const KeyBinding> binding) {
  KeySpec k = make_key(std::move(name), type, std::move(unit), std::move(description));
  k.length = std::move(length);
  k.binding = std::move(binding);
  return k;
}

KeySpec& KeySpec::require() {
  required = true;
  return *this;
}
KeySpec& KeySpec::defaults(std::string text) {
  default_text = std::move(text);
  return *this;
}
KeySpec& KeySpec::default_of_member() {
  const std::string text = binding ? binding->default_text() : "";
  if (text.empty())
    throw std::logic_error(
        fmt::format("key '{}' has no bound member with a printable default", name));
  default_text = text;
  return *this;
}
KeySpec& KeySpec::at_least(double v) {
  min = v;
  min_open = false;
  return *this;
}
KeySpec& KeySpec::greater_than(double v) {
  min = v;
  min_open = true;
  return *this;
}
KeySpec& KeySpec::at_most(double v) {
  max = v;
  max_open = false;
  return *this;
}
KeySpec& KeySpec::less_than(double v) {
  max = v;
  max_open = true;
  return *this;
}
KeySpec& KeySpec::one_of(std::vector<std::string> values) {
  allowed = std::move(values);
  return *this;
}
KeySpec& KeySpec::nonempty() {
  non_empty = true;
  return *this;
}
KeySpec& KeySpec::distinct() {
  unique = true;
  return *this;
}
KeySpec& KeySpec::with_note(std::string text) {
  note = std::move(text);
  return *this;
}

const KeySpec* TableSpec::find(std::string_view name) const {
  for (const auto& k : keys)
    if (k.name == name) return &k;
  return nullptr;
}

const TableSpec& Schema::table(std::string_view path) const {
  for (const auto& t : tables)
    if (t.path == path) return t;
  throw std::logic_error(fmt::format("schema '{}' has no table '{}'", title, path));
}

TableSpec& Schema::add_table_under(std::size_t parent, std::size_t key, std::string description,
                                   std::vector<KeySpec> keys, std::string extra_keys) {
  KeySpec& k = tables[parent].keys[key];
  const bool array = k.type == ValueType::kTableArray;
  if (!array && k.type != ValueType::kTable)
    throw std::logic_error(fmt::format("schema '{}': key '{}' is not a table", title, k.name));
  const std::string& above = tables[parent].path;
  std::string dotted;  // the path without "[]": "grains.initial"
  for (char c : above)
    if (c != '[' && c != ']') dotted += c;
  dotted += (dotted.empty() ? "" : ".") + k.name;
  k.table = (above.empty() ? "" : above + ".") + k.name + (array ? "[]" : "");
  const std::string header = array ? "[[" + dotted + "]]" : "[" + dotted + "]";
  tables.push_back(
      {k.table, header, std::move(description), std::move(keys), std::move(extra_keys)});
  return tables.back();
}

// ---------------------------------------------------------------------------------------------
// Text helpers

namespace {

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      const std::size_t cost = (a[i - 1] == b[j - 1]) ? 0 : 1;
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + cost});
      diag = up;
    }
  }
  return row[b.size()];
}

}  // namespace

namespace text {

std::string join(const std::vector<std::string>& items, std::string_view sep) {
  std::string out;
  for (const auto& s : items) {
    if (!out.empty()) out += sep;
    out += s;
  }
  return out;
}

std::string quoted(std::string_view s) {
  constexpr std::size_t kMax = 60;
  std::string out;
  for (char c : s.substr(0, kMax)) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (u < 0x20 || u == 0x7f) {
      out += fmt::format("\\x{:02x}", u);
    } else {
      out += c;
    }
  }
  if (s.size() > kMax) out += "...";
  return "\"" + out + "\"";
}

std::string unit_suffix(const KeySpec& k) {
  if (k.unit.empty() || k.unit == "-") return "";
  return " [" + k.unit + "]";
}

bool in_range(const KeySpec& k, double v) {
  if (k.min && (k.min_open ? !(v > *k.min) : !(v >= *k.min))) return false;
  if (k.max && (k.max_open ? !(v < *k.max) : !(v <= *k.max))) return false;
  return true;
}

/// "> 0", ">= 1", "< 1", "[0.5, 1]", "(0, 1)", "" for the numeric bounds of k.
std::string bounds_text(const KeySpec& k) {
  if (k.min && k.max)
    return fmt::format("{}{}, {}{}", k.min_open ? "(" : "[", number_text(*k.min),
                       number_text(*k.max), k.max_open ? ")" : "]");
  if (k.min) return fmt::format("{} {}", k.min_open ? ">" : ">=", number_text(*k.min));
  if (k.max) return fmt::format("{} {}", k.max_open ? "<" : "<=", number_text(*k.max));
  return "";
}

std::string bounds_phrase(const KeySpec& k) {
  if (k.min && k.max) return fmt::format(" in {}", bounds_text(k));
  if (k.min || k.max) return fmt::format(" {}", bounds_text(k));
  return "";
}

}  // namespace text

std::string number_text(double value) {
  return fmt::format("{}", value);
}

std::string quoted_text(const std::string& value) {
  return "\"" + value + "\"";
}

std::string bool_text(bool value) {
  return value ? "true" : "false";
}

std::string describe_node(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string:
      return "the string " + text::quoted(*node.value<std::string_view>());
    case toml::node_type::integer:
      return fmt::format("the integer {}", *node.value_exact<std::int64_t>());
    case toml::node_type::floating_point: {
      const double v = *node.value_exact<double>();
      if (std::isfinite(v) && v == std::floor(v) && std::fabs(v) < 1e15)
        return fmt::format("the float {}.0", v);
      return "the float " + number_text(v);
    }
    case toml::node_type::boolean:
      return *node.value_exact<bool>() ? "the boolean true" : "the boolean false";
    case toml::node_type::array:
      return fmt::format("an array of {} {}", node.as_array()->size(),
                         node.as_array()->size() == 1 ? "entry" : "entries");
    case toml::node_type::table:
      return "a table";
    case toml::node_type::date:
    case toml::node_type::time:
    case toml::node_type::date_time:
      return "a date/time";
    default:
      return "nothing";
  }
}

std::string nearest_name(std::string_view word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = std::numeric_limits<std::size_t>::max();
  for (const auto& c : candidates) {
    const std::size_t d = edit_distance(word, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  const std::size_t limit = std::max<std::size_t>(2, word.size() / 3);
  if (best_d == 0 || best_d > limit) return "";
  return best;
}

std::string type_text(const KeySpec& k) {
  const std::string len = k.length.empty() ? "" : " (" + k.length + ")";
  switch (k.type) {
    case ValueType::kNumber:
      return "number";
    case ValueType::kInteger:
      return "integer";
    case ValueType::kString:
      return "string";
    case ValueType::kBool:
      return "bool";
    case ValueType::kNumberArray:
      return "array of numbers" + len;
    case ValueType::kStringArray:
      return "array of strings" + len;
    case ValueType::kTable:
      return "table";
    case ValueType::kTableArray:
      return "array of tables";
  }
  return "";
}

std::string range_text(const KeySpec& k) {
  std::vector<std::string> parts;
  if (!k.allowed.empty()) {
    std::vector<std::string> q;
    for (const auto& a : k.allowed) q.push_back("`" + a + "`");
    parts.push_back((k.type == ValueType::kStringArray ? "subset of " : "one of ") +
                    text::join(q, ", "));
  }
  if (const std::string b = text::bounds_text(k); !b.empty())
    parts.push_back(k.type == ValueType::kNumberArray ? "entries " + b : b);
  if (k.non_empty) parts.push_back("non-empty");
  if (k.unique) parts.push_back("no duplicates");
  if (!k.note.empty()) parts.push_back(k.note);
  return text::join(parts, "; ");
}

std::int64_t line_of(const toml::node& node) {
  return static_cast<std::int64_t>(node.source().begin.line);
}

}  // namespace mpmcd::io
