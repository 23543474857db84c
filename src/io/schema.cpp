#include "mpmcd/io/schema.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>

#include "mpmcd/core/errors.hpp"

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

KeySpec& KeySpec::require() {
  required = true;
  return *this;
}
KeySpec& KeySpec::defaults(std::string text) {
  default_text = std::move(text);
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

std::string join(const std::vector<std::string>& items, std::string_view sep) {
  std::string out;
  for (const auto& s : items) {
    if (!out.empty()) out += sep;
    out += s;
  }
  return out;
}

/// Shortest round-trip text of a number ("-1", "0.0005", "1e+300").
std::string num_text(double v) {
  return fmt::format("{}", v);
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

}  // namespace

std::string describe_node(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string:
      return "the string " + quoted(*node.value<std::string_view>());
    case toml::node_type::integer:
      return fmt::format("the integer {}", *node.value_exact<std::int64_t>());
    case toml::node_type::floating_point: {
      const double v = *node.value_exact<double>();
      if (std::isfinite(v) && v == std::floor(v) && std::fabs(v) < 1e15)
        return fmt::format("the float {}.0", v);
      return "the float " + num_text(v);
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

namespace {

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
    return fmt::format("{}{}, {}{}", k.min_open ? "(" : "[", num_text(*k.min), num_text(*k.max),
                       k.max_open ? ")" : "]");
  if (k.min) return fmt::format("{} {}", k.min_open ? ">" : ">=", num_text(*k.min));
  if (k.max) return fmt::format("{} {}", k.max_open ? "<" : "<=", num_text(*k.max));
  return "";
}

std::string bounds_phrase(const KeySpec& k) {
  if (k.min && k.max) return fmt::format(" in {}", bounds_text(k));
  if (k.min || k.max) return fmt::format(" {}", bounds_text(k));
  return "";
}

}  // namespace

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
    parts.push_back((k.type == ValueType::kStringArray ? "subset of " : "one of ") + join(q, ", "));
  }
  if (const std::string b = bounds_text(k); !b.empty())
    parts.push_back(k.type == ValueType::kNumberArray ? "entries " + b : b);
  if (k.non_empty) parts.push_back("non-empty");
  if (k.unique) parts.push_back("no duplicates");
  if (!k.note.empty()) parts.push_back(k.note);
  return join(parts, "; ");
}

std::int64_t line_of(const toml::node& node) {
  return static_cast<std::int64_t>(node.source().begin.line);
}

// ---------------------------------------------------------------------------------------------
// TableReader

namespace {

/// "a number > 0 [m]", "an integer in [1, 8]", "a string", "an array of 2 numbers [m]".
std::string expectation(const KeySpec& k, std::size_t length) {
  const std::string b = bounds_phrase(k);
  const std::string u = unit_suffix(k);
  switch (k.type) {
    case ValueType::kNumber:
      return "a finite number" + b + u;
    case ValueType::kInteger:
      return "an integer" + b + u;
    case ValueType::kString:
      if (!k.allowed.empty()) return "one of " + join(k.allowed, ", ");
      return k.non_empty ? "a non-empty string" : "a string";
    case ValueType::kBool:
      return "a boolean (true or false)";
    case ValueType::kNumberArray: {
      const std::string n = length > 0 ? fmt::format("{} ", length) : "";
      const std::string e = b.empty() ? "" : ", each" + b;
      return fmt::format("an array of {}finite numbers{}{}", n, e, u);
    }
    case ValueType::kStringArray: {
      std::string s = k.non_empty ? "a non-empty array of strings" : "an array of strings";
      if (!k.allowed.empty()) s += " from " + join(k.allowed, ", ");
      if (k.unique) s += " without duplicates";
      return s;
    }
    case ValueType::kTable:
      return "a table";
    case ValueType::kTableArray:
      return "an array of tables ([[" + k.name + "]])";
  }
  return "";
}

/// The required length of array key `k` (0 = any) from its rule and the context's symbols.
std::size_t resolved_length(const KeySpec& k, const CheckContext& context) {
  if (k.length.empty()) return 0;
  if (auto it = context.lengths.find(k.length); it != context.lengths.end()) return it->second;
  if (std::all_of(k.length.begin(), k.length.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return static_cast<std::size_t>(std::stoul(k.length));
  throw std::logic_error(
      fmt::format("length symbol '{}' of key '{}' has no value in the context", k.length, k.name));
}

}  // namespace

TableReader::TableReader(const toml::table& table, const TableSpec& spec,
                         const CheckContext& context, std::string path, std::int64_t line,
                         std::vector<KeySpec> extra)
    : table_(table),
      spec_(spec),
      context_(context),
      path_(std::move(path)),
      line_(line),
      extra_(std::move(extra)) {
  // Unknown keys first (in file order), then values, then missing required keys.
  std::vector<std::string> known;
  for (const auto& k : spec_.keys) known.push_back(k.name);
  for (const auto& k : extra_) known.push_back(k.name);
  for (auto&& [key, node] : table_) {
    const std::string name(key.str());
    if (std::find(known.begin(), known.end(), name) != known.end()) continue;
    const std::string near = nearest_name(name, known);
    std::string msg = "unknown key";
    const TableSpec* home = nullptr;  // another table that has a key of this name
    if (context_.schema)
      for (const auto& t : context_.schema->tables)
        if (&t != &spec_ && t.find(name) && !t.header.empty()) home = &t;
    if (!near.empty())
      msg += fmt::format(", did you mean '{}'?", near);
    else if (home)
      msg += fmt::format(" here: '{}' is a key of {}", name, home->header);
    else if (!known.empty())
      msg += ", expected one of: " + join(known, ", ");
    else
      msg += ": this table takes no keys";
    throw InputError(context_.file, static_cast<std::int64_t>(key.source().begin.line),
                     key_path(name), msg);
  }
  for (auto&& [key, node] : table_) check_key(key, node);
  auto check_required = [&](const KeySpec& k) {
    if (!k.required || table_.contains(k.name)) return;
    std::string what;
    if (k.type == ValueType::kTable)
      what = fmt::format("missing required table [{}]", key_path(k.name));
    else if (k.type == ValueType::kTableArray)
      what = fmt::format("missing required table [[{}]]", key_path(k.name));
    else
      what = fmt::format("missing required key ({})", expectation(k, resolved_length(k, context_)));
    throw InputError(context_.file, line_, key_path(k.name), what);
  };
  for (const auto& k : spec_.keys) check_required(k);
  for (const auto& k : extra_) check_required(k);
}

const KeySpec& TableReader::spec_of(std::string_view key) const {
  if (const KeySpec* k = spec_.find(key)) return *k;
  for (const auto& k : extra_)
    if (k.name == key) return k;
  throw std::logic_error(fmt::format("table '{}' has no key '{}' in its schema", spec_.path, key));
}

std::string TableReader::key_path(std::string_view key) const {
  if (path_.empty()) return std::string(key);
  return path_ + "." + std::string(key);
}

bool TableReader::has(std::string_view key) const {
  return table_.contains(key);
}

std::int64_t TableReader::line(std::string_view key) const {
  if (const toml::node* n = table_.get(key)) return line_of(*n);
  return line_;
}

void TableReader::fail(std::string_view key, const std::string& expectation) const {
  throw InputError(context_.file, line(key), key_path(key), expectation);
}

void TableReader::fail_table(const std::string& expectation) const {
  throw InputError(context_.file, line_, path_, expectation);
}

void TableReader::check_key(const toml::key& key, const toml::node& node) const {
  const KeySpec& k = spec_of(key.str());
  const std::string kp = key_path(key.str());
  const std::int64_t ln = line_of(node);

  const std::size_t length = resolved_length(k, context_);
  auto type_error = [&](const toml::node& n, const std::string& where) {
    throw InputError(context_.file, line_of(n), where,
                     fmt::format("expected {}, got {}", expectation(k, length), describe_node(n)));
  };
  // An array entry is described as a single number (its own bounds and unit).
  const bool entry = k.type == ValueType::kNumberArray;
  const std::string number_expectation =
      entry ? "a finite number" + bounds_phrase(k) + unit_suffix(k) : expectation(k, length);
  auto check_number = [&](const toml::node& n, const std::string& where) {
    if (!n.is_number())
      throw InputError(context_.file, line_of(n), where,
                       fmt::format("expected {}, got {}", number_expectation, describe_node(n)));
    const double v = n.is_integer() ? static_cast<double>(*n.value_exact<std::int64_t>())
                                    : *n.value_exact<double>();
    if (!std::isfinite(v) || !in_range(k, v))
      throw InputError(context_.file, line_of(n), where,
                       fmt::format("expected {}, got {}", number_expectation, num_text(v)));
  };
  auto check_string = [&](const toml::node& n, const std::string& where) {
    if (!n.is_string() && k.type == ValueType::kStringArray)
      throw InputError(context_.file, line_of(n), where,
                       fmt::format("expected a string, got {}", describe_node(n)));
    if (!n.is_string()) type_error(n, where);
    const std::string s(*n.value_exact<std::string>());
    if (k.non_empty && s.empty() && k.type == ValueType::kString)
      throw InputError(context_.file, line_of(n), where,
                       fmt::format("expected {}, got an empty string", expectation(k, length)));
    if (!k.allowed.empty() && std::find(k.allowed.begin(), k.allowed.end(), s) == k.allowed.end()) {
      std::string msg = fmt::format("expected one of {}, got {}", join(k.allowed, ", "), quoted(s));
      if (const std::string near = nearest_name(s, k.allowed); !near.empty())
        msg += fmt::format(" (did you mean \"{}\"?)", near);
      throw InputError(context_.file, line_of(n), where, msg);
    }
  };

  switch (k.type) {
    case ValueType::kNumber:
      check_number(node, kp);
      return;
    case ValueType::kInteger: {
      if (!node.is_integer()) type_error(node, kp);
      const std::int64_t v = *node.value_exact<std::int64_t>();
      if (!in_range(k, static_cast<double>(v)))
        throw InputError(context_.file, ln, kp,
                         fmt::format("expected {}, got {}", expectation(k, length), v));
      return;
    }
    case ValueType::kString:
      check_string(node, kp);
      return;
    case ValueType::kBool:
      if (!node.is_boolean()) type_error(node, kp);
      return;
    case ValueType::kNumberArray:
    case ValueType::kStringArray: {
      const toml::array* arr = node.as_array();
      if (!arr) type_error(node, kp);
      if (length > 0 && arr->size() != length)
        throw InputError(context_.file, ln, kp,
                         fmt::format("expected {}, got {} {}", expectation(k, length), arr->size(),
                                     arr->size() == 1 ? "entry" : "entries"));
      if (k.non_empty && arr->empty())
        throw InputError(context_.file, ln, kp,
                         fmt::format("expected {}, got an empty array", expectation(k, length)));
      std::set<std::string> seen;
      for (std::size_t i = 0; i < arr->size(); ++i) {
        const toml::node& e = *arr->get(i);
        const std::string where = fmt::format("{}[{}]", kp, i);
        if (k.type == ValueType::kNumberArray) {
          check_number(e, where);
        } else {
          check_string(e, where);
          const std::string s(*e.value_exact<std::string>());
          if (k.unique && !seen.insert(s).second)
            throw InputError(
                context_.file, line_of(e), where,
                fmt::format("duplicate entry {} (expected {})", quoted(s), expectation(k, length)));
        }
      }
      return;
    }
    case ValueType::kTable:
      if (!node.is_table()) type_error(node, kp);
      return;
    case ValueType::kTableArray: {
      const toml::array* arr = node.as_array();
      if (!arr) type_error(node, kp);
      for (std::size_t i = 0; i < arr->size(); ++i)
        if (!arr->get(i)->is_table())
          throw InputError(context_.file, line_of(*arr->get(i)), fmt::format("{}[{}]", kp, i),
                           fmt::format("expected a table (as in [[{}]]), got {}", kp,
                                       describe_node(*arr->get(i))));
      if (k.non_empty && arr->empty())
        throw InputError(context_.file, ln, kp, "expected at least one table, got none");
      return;
    }
  }
}

void TableReader::read(std::string_view key, double& out) const {
  if (const toml::node* n = table_.get(key)) out = n->value<double>().value();
}

void TableReader::read(std::string_view key, std::int64_t& out) const {
  if (const toml::node* n = table_.get(key)) out = n->value_exact<std::int64_t>().value();
}

void TableReader::read(std::string_view key, int& out) const {
  const toml::node* n = table_.get(key);
  if (!n) return;
  const std::int64_t v = n->value_exact<std::int64_t>().value();
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max())
    fail(key, fmt::format("expected an integer that fits in 32 bits, got {}", v));
  out = static_cast<int>(v);
}

void TableReader::read(std::string_view key, std::string& out) const {
  if (const toml::node* n = table_.get(key)) out = n->value_exact<std::string>().value();
}

void TableReader::read(std::string_view key, bool& out) const {
  if (const toml::node* n = table_.get(key)) out = n->value_exact<bool>().value();
}

void TableReader::read(std::string_view key, std::vector<double>& out) const {
  const toml::node* n = table_.get(key);
  if (!n) return;
  out.clear();
  for (const auto& e : *n->as_array()) out.push_back(e.value<double>().value());
}

void TableReader::read(std::string_view key, std::vector<std::string>& out) const {
  const toml::node* n = table_.get(key);
  if (!n) return;
  out.clear();
  for (const auto& e : *n->as_array()) out.push_back(e.value_exact<std::string>().value());
}

const toml::table* TableReader::subtable(std::string_view key) const {
  const toml::node* n = table_.get(key);
  return n ? n->as_table() : nullptr;
}

std::vector<const toml::table*> TableReader::table_array(std::string_view key) const {
  std::vector<const toml::table*> out;
  if (const toml::node* n = table_.get(key))
    for (const auto& e : *n->as_array()) out.push_back(e.as_table());
  return out;
}

// ---------------------------------------------------------------------------------------------
// Markdown

std::string markdown_cell(std::string_view text) {
  std::string out;
  for (char c : text) {
    if (c == '|')
      out += "\\|";
    else if (c == '\n')
      out += ' ';
    else
      out += c;
  }
  return out;
}

std::string schema_markdown(const Schema& schema) {
  std::string md = "# " + schema.title + "\n\n";
  if (!schema.description.empty()) md += schema.description + "\n\n";
  for (const auto& t : schema.tables) {
    md += "## " + (t.header.empty() ? std::string("Top level") : "`" + t.header + "`") + "\n\n";
    if (!t.description.empty()) md += t.description + "\n\n";
    if (!t.keys.empty()) {
      md += "| key | type | default | range / allowed | unit | description |\n";
      md += "|---|---|---|---|---|---|\n";
      for (const auto& k : t.keys) {
        const std::string path = t.path.empty() ? k.name : t.path + "." + k.name;
        const std::string def = k.required               ? "**required**"
                                : k.default_text.empty() ? "–"
                                                         : "`" + k.default_text + "`";
        const std::string unit = (k.unit.empty() || k.unit == "-") ? "–" : k.unit;
        const std::string range = range_text(k).empty() ? "–" : range_text(k);
        md += fmt::format("| `{}` | {} | {} | {} | {} | {} |\n", path, markdown_cell(type_text(k)),
                          markdown_cell(def), markdown_cell(range), markdown_cell(unit),
                          markdown_cell(k.description));
      }
      md += "\n";
    }
    if (!t.extra_keys.empty()) md += t.extra_keys + "\n\n";
  }
  while (md.size() >= 2 && md[md.size() - 1] == '\n' && md[md.size() - 2] == '\n') md.pop_back();
  return md;
}

}  // namespace mpmcd::io
