#pragma once
/// A small, generic description of a TOML input (tables, keys, types, ranges, units), a checker
/// that validates a parsed toml++ table against it and throws InputError (file:line, dotted key,
/// expectation), and a Markdown renderer for the input reference. Nothing here knows about a
/// particular input: the simulation schema lives in io/config.cpp, a packing input may add its own.
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <toml++/toml.h>

namespace mpmcd::io {

/// Type of the value under a key.
enum class ValueType {
  kNumber,       ///< float or integer (an integer is accepted where a number is expected)
  kInteger,      ///< integer only
  kString,       ///< string
  kBool,         ///< true / false
  kNumberArray,  ///< array of numbers
  kStringArray,  ///< array of strings
  kTable,        ///< a sub-table, described by another TableSpec
  kTableArray,   ///< an array of tables ([[name]]), described by another TableSpec
};

/// One key of a table: type, presence, default, range or allowed values, unit, description.
struct KeySpec {
  std::string name;                     ///< key inside its table, e.g. "cell_size"
  ValueType type = ValueType::kNumber;  ///< expected type
  std::string unit;                     ///< SI unit ("m", "Pa", ...), "" or "-" if dimensionless
  std::string description;              ///< one line
  bool required = false;                ///< true: the key must be present
  std::string default_text;   ///< documented default when optional ("" = absent means unset)
  std::optional<double> min;  ///< lower bound of numbers / integers (also of array entries)
  bool min_open = false;      ///< true: bound is exclusive (> min), false: inclusive (>= min)
  std::optional<double> max;  ///< upper bound of numbers / integers (also of array entries)
  bool max_open = false;      ///< true: bound is exclusive (< max)
  std::vector<std::string> allowed;  ///< allowed strings (string, string array); empty = any
  std::string length;      ///< array length rule: "" any, a number, or a symbol from CheckContext
  bool non_empty = false;  ///< strings and arrays: must not be empty
  bool unique = false;     ///< arrays: no duplicate entries
  std::string table;       ///< kTable / kTableArray: path of the TableSpec describing it
  std::string note;        ///< extra documentation (e.g. "disk only"), shown with the range

  /// A number key [unit].
  static KeySpec number(std::string name, std::string unit, std::string description);
  /// An integer key.
  static KeySpec integer(std::string name, std::string unit, std::string description);
  /// A string key.
  static KeySpec string(std::string name, std::string description);
  /// A boolean key.
  static KeySpec boolean(std::string name, std::string description);
  /// An array of numbers whose length follows `length` ("Dim", "Dim*Dim", "3", "").
  static KeySpec numbers(std::string name, std::string length, std::string unit,
                         std::string description);
  /// An array of strings.
  static KeySpec strings(std::string name, std::string description);
  /// A sub-table described by the TableSpec at `table_path`.
  static KeySpec subtable(std::string name, std::string table_path, std::string description);
  /// An array of tables described by the TableSpec at `table_path`.
  static KeySpec table_array(std::string name, std::string table_path, std::string description);

  KeySpec& require();                                ///< marks the key required
  KeySpec& defaults(std::string text);               ///< documented default of an optional key
  KeySpec& at_least(double v);                       ///< value >= v
  KeySpec& greater_than(double v);                   ///< value > v
  KeySpec& at_most(double v);                        ///< value <= v
  KeySpec& less_than(double v);                      ///< value < v
  KeySpec& one_of(std::vector<std::string> values);  ///< allowed strings
  KeySpec& nonempty();                               ///< non-empty string or array
  KeySpec& distinct();                               ///< array entries unique
  KeySpec& with_note(std::string text);              ///< extra documentation
};

/// A table of the input: its path, how it appears in TOML, its keys.
struct TableSpec {
  std::string path;           ///< dotted path of its keys, "" for the root, e.g. "grains[].initial"
  std::string header;         ///< as written in TOML, e.g. "[grid]", "[[grains]]"
  std::string description;    ///< a paragraph
  std::vector<KeySpec> keys;  ///< its keys, in documentation order
  std::string extra_keys;     ///< documents keys added at check time ("" = none allowed)

  const KeySpec* find(std::string_view name) const;  ///< key by name, nullptr if unknown
};

/// A whole input: its tables, the root first.
struct Schema {
  std::string title;              ///< document title
  std::string description;        ///< introduction paragraph (Markdown)
  std::vector<TableSpec> tables;  ///< root (path "") first, then in documentation order

  const TableSpec& table(std::string_view path) const;  ///< by path; throws std::logic_error
};

/// Values of symbolic array lengths, e.g. {{"Dim", 2}, {"Dim*Dim", 4}}.
struct CheckContext {
  std::string file;                            ///< file name used in messages
  std::map<std::string, std::size_t> lengths;  ///< symbol -> length
  const Schema* schema = nullptr;  ///< if set, unknown keys found in another table are pointed to
};

/// The closest candidate to `word` by edit distance if it is close enough, else "".
std::string nearest_name(std::string_view word, const std::vector<std::string>& candidates);

/// Human text of a key's type ("number", "array of numbers (Dim)").
std::string type_text(const KeySpec& key);
/// Human text of a key's range / allowed values ("> 0", "[0.5, 1]", "one of: a, b").
std::string range_text(const KeySpec& key);

/// What a node holds, for "got ..." in messages: `the string "abc"`, `the float 2.0`, `a table`.
std::string describe_node(const toml::node& node);

/// 1-based line of a toml++ node (0 if unknown).
std::int64_t line_of(const toml::node& node);

/// Reads one validated table. The constructor checks every key of `table` against `spec` plus
/// `extra` keys: unknown keys (with the nearest known name), types, ranges, NaN/Inf, allowed
/// strings, array lengths, uniqueness, required keys; sub-tables are checked when they are read.
/// Every error is an InputError(file, line, "path.key", expectation).
class TableReader {
 public:
  /// `path` names the table in messages, e.g. "grains[2]"; `line` is its line (0 if unknown).
  TableReader(const toml::table& table, const TableSpec& spec, const CheckContext& context,
              std::string path, std::int64_t line, std::vector<KeySpec> extra = {});

  bool has(std::string_view key) const;                ///< present in the input
  std::int64_t line() const { return line_; }          ///< line of the table
  std::int64_t line(std::string_view key) const;       ///< line of a key (table line if absent)
  const std::string& path() const { return path_; }    ///< path used in messages
  std::string key_path(std::string_view key) const;    ///< "path.key"
  const toml::table& table() const { return table_; }  ///< the underlying table

  /// Each `read` assigns `out` only when the key is present (defaults stay as they are).
  void read(std::string_view key, double& out) const;                    ///< number
  void read(std::string_view key, int& out) const;                       ///< integer (in range)
  void read(std::string_view key, std::int64_t& out) const;              ///< integer
  void read(std::string_view key, std::string& out) const;               ///< string
  void read(std::string_view key, bool& out) const;                      ///< bool
  void read(std::string_view key, std::vector<double>& out) const;       ///< number array
  void read(std::string_view key, std::vector<std::string>& out) const;  ///< string array

  /// The sub-table under `key` (nullptr if absent).
  const toml::table* subtable(std::string_view key) const;
  /// The tables of the array of tables under `key` (empty if absent).
  std::vector<const toml::table*> table_array(std::string_view key) const;

  /// Throws InputError at the line of `key` (of the table if absent) for "path.key".
  [[noreturn]] void fail(std::string_view key, const std::string& expectation) const;
  /// Throws InputError at the table's line, for the table itself.
  [[noreturn]] void fail_table(const std::string& expectation) const;

 private:
  const KeySpec& spec_of(std::string_view key) const;
  void check_key(const toml::key& key, const toml::node& node) const;

  const toml::table& table_;
  const TableSpec& spec_;
  const CheckContext& context_;
  std::string path_;
  std::int64_t line_ = 0;
  std::vector<KeySpec> extra_;
};

/// Renders the reference of `schema` as Markdown: one section per table with a table of
/// key | type | default | range / allowed | unit | description.
std::string schema_markdown(const Schema& schema);

/// Escapes text for a Markdown table cell ('|' and newlines).
std::string markdown_cell(std::string_view text);

}  // namespace mpmcd::io
