// TableReader: checks one TOML table against its TableSpec (unknown keys, types, ranges, lengths,
// required keys) with messages file:line: key 'path.key': expectation, then reads its values.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/io/schema.hpp"
#include "schema_text.hpp"

namespace mpmcd::io {

namespace {

using text::bounds_phrase;
using text::in_range;
using text::join;
using text::quoted;
using text::unit_suffix;

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
                       fmt::format("expected {}, got {}", number_expectation, number_text(v)));
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

std::string TableReader::element_path(std::string_view key, std::size_t index) const {
  return fmt::format("{}[{}]", key_path(key), index);
}

const TableSpec& TableReader::table_spec(const KeySpec& key) const {
  if (!context_.schema)
    throw std::logic_error(
        fmt::format("table '{}': sub-table '{}' read without a schema in the "
                    "context",
                    spec_.path, key.name));
  return context_.schema->table(key.table);
}

TableReader TableReader::sub_reader(const KeySpec& key) const {
  static const toml::table empty;
  const toml::table* t = subtable(key.name);
  return TableReader(t ? *t : empty, table_spec(key), context_, key_path(key.name),
                     t ? line_of(*t) : 0);
}

TableReader TableReader::element_reader(const KeySpec& key, std::size_t index,
                                        const toml::table& table,
                                        std::vector<KeySpec> extra) const {
  return TableReader(table, table_spec(key), context_, element_path(key.name, index),
                     line_of(table), std::move(extra));
}

}  // namespace mpmcd::io
