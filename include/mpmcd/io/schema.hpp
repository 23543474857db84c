#pragma once
/// A small, generic description of a TOML input (tables, keys, types, ranges, units), a checker
/// that validates a parsed toml++ table against it and throws InputError (file:line, dotted key,
/// expectation), and a Markdown renderer for the input reference. Nothing here knows about a
/// particular input: the simulation schema lives in io/config.cpp, a packing input may add its own.
///
/// A key may be bound to the member of a section struct that it fills (`KeySpec::number("dt",
/// &TimeSection::dt, ...)`): the factory only accepts a member of the C++ type that matches the
/// key's ValueType, `TableReader::fill` then assigns every bound key that is present, and the
/// hand-written checks name a key by its member (`r.fail(&TimeSection::dt, ...)`), so that the
/// key's name is written once, in its declaration.
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <toml++/toml.h>

namespace mpmcd::io {

class TableReader;

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

/// The member a key fills, type-erased (see MemberBinding).
class KeyBinding {
 public:
  virtual ~KeyBinding() = default;
  /// The member's value in a default-constructed section as documentation text ("" if it has
  /// none: arrays, tables).
  virtual std::string default_text() const = 0;
};

/// A binding into a member of the section struct S.
template <class S>
class SectionBinding : public KeyBinding {
 public:
  /// Assigns the member of `section` from key `name` of `reader` if the key is present (tables
  /// and arrays of tables are left to the caller).
  virtual void fill(const TableReader& reader, std::string_view name, S& section) const = 0;
};

/// The C++ types a value key can fill: one per ValueType except the tables.
template <class M>
concept KeyValue = std::same_as<M, double> || std::same_as<M, int> ||
    std::same_as<M, std::int64_t> || std::same_as<M, std::string> || std::same_as<M, bool> ||
    std::same_as<M, std::vector<double>> || std::same_as<M, std::vector<std::string>>;

/// A binding to the member `member` (of type M) of the section struct S.
template <class S, class M>
class MemberBinding final : public SectionBinding<S> {
 public:
  /// Binds `member`.
  explicit MemberBinding(M S::*member) : member_(member) {}
  /// The bound member.
  M S::*member() const { return member_; }
  /// See KeyBinding::default_text.
  std::string default_text() const override;
  /// See SectionBinding::fill.
  void fill(const TableReader& reader, std::string_view name, S& section) const override;

 private:
  M S::*member_;
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
  std::shared_ptr<const KeyBinding> binding;  ///< the member it fills (nullptr: read by hand)

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

  /// A number key [unit] that fills `member`.
  template <class S>
  static KeySpec number(std::string name, double S::*member, std::string unit,
                        std::string description);
  /// An integer key that fills `member` (int or std::int64_t).
  template <class S, class I>
  requires std::same_as<I, int> || std::same_as<I, std::int64_t>
  static KeySpec integer(std::string name, I S::*member, std::string unit, std::string description);
  /// A string key that fills `member`.
  template <class S>
  static KeySpec string(std::string name, std::string S::*member, std::string description);
  /// A boolean key that fills `member`.
  template <class S>
  static KeySpec boolean(std::string name, bool S::*member, std::string description);
  /// An array of numbers (length rule `length`) that fills `member`.
  template <class S>
  static KeySpec numbers(std::string name, std::vector<double> S::*member, std::string length,
                         std::string unit, std::string description);
  /// An array of strings that fills `member`.
  template <class S>
  static KeySpec strings(std::string name, std::vector<std::string> S::*member,
                         std::string description);
  /// A sub-table read into the section `member`; its TableSpec is added by Schema::add_table.
  template <class S, class T>
  requires std::is_class_v<T>
  static KeySpec subtable(std::string name, T S::*member, std::string description);
  /// An array of tables read into `member`; its TableSpec is added by Schema::add_table.
  template <class S, class E>
  requires std::is_class_v<E>
  static KeySpec table_array(std::string name, std::vector<E> S::*member, std::string description);

  KeySpec& require();                   ///< marks the key required
  KeySpec& defaults(std::string text);  ///< documented default of an optional key
  KeySpec& default_of_member();         ///< documented default: the bound member's initial value
  KeySpec& at_least(double v);          ///< value >= v
  KeySpec& greater_than(double v);      ///< value > v
  KeySpec& at_most(double v);           ///< value <= v
  KeySpec& less_than(double v);         ///< value < v
  KeySpec& one_of(std::vector<std::string> values);  ///< allowed strings
  KeySpec& nonempty();                               ///< non-empty string or array
  KeySpec& distinct();                               ///< array entries unique
  KeySpec& with_note(std::string text);              ///< extra documentation

  /// True if this key fills `member`.
  template <class S, class M>
  bool binds(M S::*member) const;

 private:
  static KeySpec bound(std::string name, ValueType type, std::string length, std::string unit,
                       std::string description, std::shared_ptr<const KeyBinding> binding);
};

/// A table of the input: its path, how it appears in TOML, its keys.
struct TableSpec {
  std::string path;           ///< dotted path of its keys, "" for the root, e.g. "grains[].initial"
  std::string header;         ///< as written in TOML, e.g. "[grid]", "[[grains]]"
  std::string description;    ///< a paragraph
  std::vector<KeySpec> keys;  ///< its keys, in documentation order
  std::string extra_keys;     ///< documents keys added at check time ("" = none allowed)

  const KeySpec* find(std::string_view name) const;  ///< key by name, nullptr if unknown
  /// The key that fills `member`, nullptr if none.
  template <class S, class M>
  const KeySpec* find(M S::*member) const;
};

/// A whole input: its tables, the root first.
struct Schema {
  std::string title;              ///< document title
  std::string description;        ///< introduction paragraph (Markdown)
  std::vector<TableSpec> tables;  ///< root (path "") first, then in documentation order

  const TableSpec& table(std::string_view path) const;  ///< by path; throws std::logic_error

  /// Adds the table held by the (sub-table or table-array) key bound to `member`, a key of a
  /// table already added: its path and header follow from that key's ("grains[].initial",
  /// "[grains.initial]"), and the key is pointed to it. Throws std::logic_error if no key binds
  /// `member`.
  template <class S, class M>
  TableSpec& add_table(M S::*member, std::string description, std::vector<KeySpec> keys,
                       std::string extra_keys = "");

 private:
  TableSpec& add_table_under(std::size_t parent, std::size_t key, std::string description,
                             std::vector<KeySpec> keys, std::string extra_keys);
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

/// Shortest round-trip text of a number ("0.5", "1e-08", "2").
std::string number_text(double value);
/// A string in double quotes, as a documented default ("\"linear\"").
std::string quoted_text(const std::string& value);
/// "true" or "false".
std::string bool_text(bool value);

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

  /// Assigns every key of the table that is bound to a member of S and present in the input
  /// (in the table's key order); sub-tables and arrays of tables are read with `sub` / `element`.
  /// Throws std::logic_error if a key is bound to another struct.
  template <class S>
  void fill(S& section) const;

  /// The key bound to `member` (throws std::logic_error if no key of the table binds it).
  template <class S, class M>
  const KeySpec& key(M S::*member) const;
  /// The name of the key bound to `member`.
  template <class S, class M>
  const std::string& name(M S::*member) const {
    return key(member).name;
  }
  /// True if the key bound to `member` is present in the input.
  template <class S, class M>
  bool has(M S::*member) const {
    return has(key(member).name);
  }
  /// Line of the key bound to `member` (the table's line if absent).
  template <class S, class M>
  std::int64_t line(M S::*member) const {
    return line(key(member).name);
  }
  /// Throws InputError for the key bound to `member` (see fail).
  template <class S, class M>
  [[noreturn]] void fail(M S::*member, const std::string& expectation) const {
    fail(key(member).name, expectation);
  }
  /// The checked reader of the sub-table bound to `member` (an empty table if absent).
  template <class S, class T>
  TableReader sub(T S::*member) const {
    return sub_reader(key(member));
  }
  /// The tables of the array of tables bound to `member` (empty if absent).
  template <class S, class E>
  std::vector<const toml::table*> tables(std::vector<E> S::*member) const {
    return table_array(key(member).name);
  }
  /// The checked reader of `table`, entry `index` of the array of tables bound to `member`,
  /// with the keys `extra` allowed besides its schema's.
  template <class S, class E>
  TableReader element(std::vector<E> S::*member, std::size_t index, const toml::table& table,
                      std::vector<KeySpec> extra = {}) const {
    return element_reader(key(member), index, table, std::move(extra));
  }
  /// "path.key[index]": the path of an entry of the array of tables under `key`.
  std::string element_path(std::string_view key, std::size_t index) const;

 private:
  const KeySpec& spec_of(std::string_view key) const;
  void check_key(const toml::key& key, const toml::node& node) const;
  const TableSpec& table_spec(const KeySpec& key) const;
  TableReader sub_reader(const KeySpec& key) const;
  TableReader element_reader(const KeySpec& key, std::size_t index, const toml::table& table,
                             std::vector<KeySpec> extra) const;

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

// ---------------------------------------------------------------------------------------------
// Template definitions

template <class S, class M>
std::string MemberBinding<S, M>::default_text() const {
  if constexpr (std::same_as<M, bool>)
    return bool_text(S{}.*member_);
  else if constexpr (std::is_arithmetic_v<M>)
    return number_text(static_cast<double>(S{}.*member_));
  else if constexpr (std::same_as<M, std::string>)
    return quoted_text(S{}.*member_);
  else
    return "";  // arrays and tables: documented by hand ("zeros", "its defaults")
}

template <class S, class M>
void MemberBinding<S, M>::fill(const TableReader& reader, std::string_view name, S& section) const {
  if constexpr (KeyValue<M>) reader.read(name, section.*member_);
}

/// The binding of `member`.
template <class S, class M>
std::shared_ptr<const KeyBinding> make_binding(M S::*member) {
  return std::make_shared<const MemberBinding<S, M>>(member);
}

template <class S>
KeySpec KeySpec::number(std::string name, double S::*member, std::string unit,
                        std::string description) {
  return bound(std::move(name), ValueType::kNumber, "", std::move(unit), std::move(description),
               io::make_binding(member));
}

template <class S, class I>
requires std::same_as<I, int> || std::same_as<I, std::int64_t> KeySpec
KeySpec::integer(std::string name, I S::*member, std::string unit, std::string description) {
  return bound(std::move(name), ValueType::kInteger, "", std::move(unit), std::move(description),
               io::make_binding(member));
}

template <class S>
KeySpec KeySpec::string(std::string name, std::string S::*member, std::string description) {
  return bound(std::move(name), ValueType::kString, "", "", std::move(description),
               io::make_binding(member));
}

template <class S>
KeySpec KeySpec::boolean(std::string name, bool S::*member, std::string description) {
  return bound(std::move(name), ValueType::kBool, "", "", std::move(description),
               io::make_binding(member));
}

template <class S>
KeySpec KeySpec::numbers(std::string name, std::vector<double> S::*member, std::string length,
                         std::string unit, std::string description) {
  return bound(std::move(name), ValueType::kNumberArray, std::move(length), std::move(unit),
               std::move(description), io::make_binding(member));
}

template <class S>
KeySpec KeySpec::strings(std::string name, std::vector<std::string> S::*member,
                         std::string description) {
  return bound(std::move(name), ValueType::kStringArray, "", "", std::move(description),
               io::make_binding(member));
}

template <class S, class T>
requires std::is_class_v<T> KeySpec KeySpec::subtable(std::string name, T S::*member,
                                                      std::string description) {
  return bound(std::move(name), ValueType::kTable, "", "", std::move(description),
               io::make_binding(member));
}

template <class S, class E>
requires std::is_class_v<E> KeySpec KeySpec::table_array(std::string name,
                                                         std::vector<E> S::*member,
                                                         std::string description) {
  return bound(std::move(name), ValueType::kTableArray, "", "", std::move(description),
               io::make_binding(member));
}

template <class S, class M>
bool KeySpec::binds(M S::*member) const {
  const auto* b = dynamic_cast<const MemberBinding<S, M>*>(binding.get());
  return b != nullptr && b->member() == member;
}

template <class S, class M>
const KeySpec* TableSpec::find(M S::*member) const {
  for (const auto& k : keys)
    if (k.binds(member)) return &k;
  return nullptr;
}

template <class S, class M>
TableSpec& Schema::add_table(M S::*member, std::string description, std::vector<KeySpec> keys,
                             std::string extra_keys) {
  for (std::size_t t = 0; t < tables.size(); ++t)
    for (std::size_t k = 0; k < tables[t].keys.size(); ++k)
      if (tables[t].keys[k].binds(member))
        return add_table_under(t, k, std::move(description), std::move(keys),
                               std::move(extra_keys));
  throw std::logic_error("schema '" + title + "': add_table of a member that no key binds");
}

template <class S>
void TableReader::fill(S& section) const {
  for (const auto& k : spec_.keys) {
    if (!k.binding) continue;
    const auto* b = dynamic_cast<const SectionBinding<S>*>(k.binding.get());
    if (!b) throw std::logic_error("key '" + key_path(k.name) + "' is bound to another struct");
    b->fill(*this, k.name, section);
  }
}

template <class S, class M>
const KeySpec& TableReader::key(M S::*member) const {
  const KeySpec* k = spec_.find(member);
  if (!k) throw std::logic_error("no key of table '" + spec_.path + "' binds this member");
  return *k;
}

}  // namespace mpmcd::io
