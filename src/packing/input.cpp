// The packing input file (docs/packing.md §5).
#include "mpmcd/packing/input.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <string_view>

#include "mpmcd/core/errors.hpp"
#include "params_check.hpp"

namespace mpmcd::packing {

namespace {

// Largest input file parsed [bytes]: an explicit list of kMaxDisks diameters fits easily.
constexpr std::uintmax_t kMaxInputBytes = std::uintmax_t{64} << 20;

std::int64_t line_of(const toml::node& node, std::int64_t fallback) {
  const auto line = static_cast<std::int64_t>(node.source().begin.line);
  return line > 0 ? line : fallback;
}

std::string type_name(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a float";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::table:
      return "a table";
    default:
      return "a date/time";
  }
}

// Typed access to the keys of one table, with file:line errors.
class Keys {
 public:
  Keys(const toml::table& table, std::string file, std::string prefix, std::int64_t line,
       std::set<std::string> known)
      : table_(table),
        file_(std::move(file)),
        prefix_(std::move(prefix)),
        line_(line),
        known_(std::move(known)) {
    for (const auto& [key, node] : table_) {
      const std::string name(key.str());
      if (!known_.count(name)) {
        std::string list;
        for (const auto& k : known_) list += (list.empty() ? "" : ", ") + k;
        throw InputError(file_, line_of(node, line_), path(name),
                         fmt::format("unknown key; known keys of [{}]: {}", prefix_, list));
      }
    }
  }
  std::string path(std::string_view key) const { return prefix_ + "." + std::string(key); }
  bool has(std::string_view key) const { return table_.contains(key); }
  std::int64_t line(std::string_view key) const {
    const auto* node = table_.get(key);
    return node ? line_of(*node, line_) : line_;
  }
  [[noreturn]] void fail(std::string_view key, const std::string& what) const {
    throw InputError(file_, line(key), path(key), what);
  }
  const toml::node& node(std::string_view key) const { return *table_.get(key); }

  double number(std::string_view key, double fallback) const {
    if (!has(key)) return fallback;
    return as_number(node(key), key, "");
  }
  std::int64_t integer(std::string_view key, std::int64_t fallback) const {
    if (!has(key)) return fallback;
    const auto* v = node(key).as_integer();
    if (!v) fail(key, "an integer, got " + type_name(node(key)));
    return v->get();
  }
  std::string string(std::string_view key, const std::string& fallback) const {
    if (!has(key)) return fallback;
    const auto* v = node(key).as_string();
    if (!v) fail(key, "a string, got " + type_name(node(key)));
    return v->get();
  }
  std::string choice(std::string_view key, const std::string& fallback,
                     const std::vector<std::string>& allowed) const {
    const std::string v = string(key, fallback);
    if (std::find(allowed.begin(), allowed.end(), v) == allowed.end()) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "\"" : ", \"") + a + "\"";
      fail(key, fmt::format("one of {}, got \"{}\"", list, v));
    }
    return v;
  }
  bool boolean(std::string_view key, bool fallback) const {
    if (!has(key)) return fallback;
    const auto* v = node(key).as_boolean();
    if (!v) fail(key, "true or false, got " + type_name(node(key)));
    return v->get();
  }
  // An array of numbers; `length` 0 = any non-empty length up to `max_length`.
  std::vector<double> numbers(std::string_view key, std::size_t length,
                              std::size_t max_length) const {
    const auto* arr = node(key).as_array();
    if (!arr) fail(key, "an array of numbers, got " + type_name(node(key)));
    if (length > 0 && arr->size() != length)
      fail(key, fmt::format("an array of {} numbers, got {}", length, arr->size()));
    if (arr->empty()) fail(key, "a non-empty array of numbers");
    if (arr->size() > max_length)
      fail(key, fmt::format("at most {} entries, got {}", max_length, arr->size()));
    std::vector<double> out;
    out.reserve(arr->size());
    for (std::size_t i = 0; i < arr->size(); ++i)
      out.push_back(as_number(*arr->get(i), key, fmt::format(" (entry {})", i + 1)));
    return out;
  }

 private:
  double as_number(const toml::node& n, std::string_view key, const std::string& where) const {
    double v = 0.0;
    if (const auto* f = n.as_floating_point())
      v = f->get();
    else if (const auto* i = n.as_integer())
      v = static_cast<double>(i->get());
    else
      throw InputError(file_, line_of(n, line(key)), path(key),
                       "a number" + where + ", got " + type_name(n));
    if (!std::isfinite(v))
      throw InputError(file_, line_of(n, line(key)), path(key),
                       "a finite number" + where + ", got " + fmt::format("{}", v));
    return v;
  }

  const toml::table& table_;
  std::string file_, prefix_;
  std::int64_t line_;
  std::set<std::string> known_;
};

}  // namespace

PackingParams packing_params_from_toml(const toml::table& table, const std::string& file,
                                       const std::string& prefix) {
  const std::int64_t table_line = line_of(table, 0);
  const Keys k(table, file, prefix, table_line, {"dimension",       "count",
                                                 "diameter_min",    "diameter_max",
                                                 "diameters",       "box",
                                                 "aspect_ratio",    "origin",
                                                 "target_phi",      "method",
                                                 "contact_law",     "friction",
                                                 "boundary",        "seed",
                                                 "initial_phi",     "growth_steps",
                                                 "max_relax_steps", "overlap_tolerance",
                                                 "damping_ratio",   "global_damping",
                                                 "jam_start_phi",   "jam_phi_tolerance"});
  PackingParams p;
  const auto table_fail = [&](const std::string& what) {
    throw InputError(file, table_line, prefix, what);
  };

  // Dimension first: it sets the length of box and origin and the jam_start_phi default.
  if (k.has("dimension")) {
    const std::int64_t dim = k.integer("dimension", 2);
    if (dim != 2 && dim != 3)
      k.fail("dimension", fmt::format("2 (disks) or 3 (spheres), got {}", dim));
    p.dimension = static_cast<int>(dim);
  }
  const bool three = p.dimension == 3;
  const std::string method = k.choice("method", "grow", {"grow", "walls", "jam"});
  p.method = method == "grow"    ? PackingMethod::kGrow
             : method == "walls" ? PackingMethod::kWalls
                                 : PackingMethod::kJam;
  p.contact_law = k.choice("contact_law", "linear", {"linear", "hertz"}) == "linear"
                      ? ContactLaw::kLinear
                      : ContactLaw::kHertz;
  p.periodic = k.choice("boundary", "walls", {"walls", "periodic"}) == "periodic";

  // Sizes: an explicit list, or count + uniform [diameter_min, diameter_max].
  const auto max_disks = static_cast<std::size_t>(kMaxDisks);
  if (k.has("diameters")) {
    for (const char* other : {"diameter_min", "diameter_max"})
      if (k.has(other))
        k.fail(other,
               "either 'diameters' (explicit list) or 'diameter_min'/'diameter_max', "
               "not both");
    p.diameters = k.numbers("diameters", 0, max_disks);
    if (k.has("count") && k.integer("count", 0) != static_cast<std::int64_t>(p.diameters.size()))
      k.fail("count", fmt::format("the length of 'diameters' ({}) or no count, got {}",
                                  p.diameters.size(), k.integer("count", 0)));
  } else {
    if (!k.has("count"))
      table_fail(
          "a key 'count' (number of disks) with 'diameter_min' and 'diameter_max', or "
          "an explicit 'diameters' list");
    for (const char* key : {"diameter_min", "diameter_max"})
      if (!k.has(key))
        table_fail(fmt::format("a key '{}' [m] (or an explicit 'diameters' list)", key));
    p.count = k.integer("count", p.count);
    p.diameter_min = k.number("diameter_min", 0.0);
    p.diameter_max = k.number("diameter_max", 0.0);
  }

  // Box: given, or aspect ratio (+ origin) and the size from target_phi.
  if (k.has("box") == k.has("aspect_ratio"))
    table_fail(three ? "exactly one of 'box' = [xmin, ymin, zmin, xmax, ymax, zmax] (m) or "
                       "'aspect_ratio' (width / height, width along x and y, height along z; the "
                       "size then follows from target_phi)"
                     : "exactly one of 'box' = [xmin, ymin, xmax, ymax] (m) or 'aspect_ratio' "
                       "(width / height, the size then follows from target_phi)");
  if (k.has("box")) {
    if (k.has("origin")) k.fail("origin", "no 'origin' with 'box' (only with 'aspect_ratio')");
    if (three) {
      const auto b = k.numbers("box", 6, 6);
      p.box = std::array<double, 4>{b[0], b[1], b[3], b[4]};
      p.box_z = {b[2], b[5]};
    } else {
      const auto b = k.numbers("box", 4, 4);
      p.box = std::array<double, 4>{b[0], b[1], b[2], b[3]};
    }
  } else {
    p.aspect_ratio = k.number("aspect_ratio", p.aspect_ratio);
    if (k.has("origin")) {
      const auto o = k.numbers("origin", three ? 3 : 2, three ? 3 : 2);
      p.origin = {o[0], o[1]};
      if (three) p.origin_z = o[2];
    }
  }
  if (p.method == PackingMethod::kJam) {
    if (k.has("target_phi"))
      k.fail("target_phi", "no target_phi with method \"jam\" (it compresses until jammed)");
  } else {
    if (!k.has("target_phi")) table_fail("a key 'target_phi' (packing fraction to reach)");
    p.target_phi = k.number("target_phi", p.target_phi);
  }
  p.friction = k.number("friction", p.friction);
  const std::int64_t seed = k.integer("seed", static_cast<std::int64_t>(p.seed));
  if (seed < 0) k.fail("seed", fmt::format("an integer >= 0, got {}", seed));
  p.seed = static_cast<std::uint64_t>(seed);
  p.initial_phi = k.number("initial_phi", p.initial_phi);
  p.growth_steps = k.integer("growth_steps", p.growth_steps);
  p.max_relax_steps = k.integer("max_relax_steps", p.max_relax_steps);
  p.overlap_tolerance = k.number("overlap_tolerance", p.overlap_tolerance);
  p.damping_ratio = k.number("damping_ratio", p.damping_ratio);
  p.global_damping = k.number("global_damping", p.global_damping);
  // Spheres jam near 0.64 (random close packing), disks near 0.84: the search starts below.
  p.jam_start_phi = k.number("jam_start_phi", three ? kJamStartPhi3D : p.jam_start_phi);
  p.jam_phi_tolerance = k.number("jam_phi_tolerance", p.jam_phi_tolerance);

  if (auto problem = detail::check_params(p)) {
    // Report at the key's line when it is present, else at the table's line.
    const auto line = k.has(problem->key) ? k.line(problem->key) : table_line;
    throw InputError(file, line, k.path(problem->key), problem->expectation);
  }
  return p;
}

PackingInput load_packing_input(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(path, 0, "", "a readable packing input file (TOML); it is a directory");
  if (!std::filesystem::is_regular_file(path, ec))
    throw InputError(path, 0, "", "a readable packing input file (TOML); it does not exist");
  const auto bytes = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path, 0, "", "a readable file: " + ec.message());
  if (bytes > kMaxInputBytes)
    throw InputError(
        path, 0, "",
        fmt::format("an input file of at most {} bytes, got {}", kMaxInputBytes, bytes));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "", "a readable packing input file (TOML)");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return parse_packing_input(buffer.str(), path);
}

PackingInput parse_packing_input(std::string_view text, const std::string& path) {
  toml::table root;
  try {
    root = toml::parse(text, std::string_view(path));
  } catch (const toml::parse_error& e) {
    throw InputError(path, static_cast<std::int64_t>(e.source().begin.line), "",
                     fmt::format("valid TOML: {}", e.description()));
  }
  // The missing [packing] table first (the keys come in alphabetical order, so a simulation input
  // would otherwise be blamed for its first table, e.g. [contact]).
  if (!root.contains("packing")) {
    const bool simulation = root.contains("grid") || root.contains("grains") ||
                            root.contains("materials") || root.contains("time");
    throw InputError(path, 0, "packing",
                     simulation ? "a [packing] table (docs/packing.md §5): this looks like a "
                                  "simulation input, which `mpmcd run` takes (a simulation makes "
                                  "its packing from [[grains]] shape = \"packing\")"
                                : "a [packing] table (docs/packing.md §5); the file has none");
  }
  for (const auto& [key, node] : root) {
    const std::string name(key.str());
    if (name != "packing" && name != "output")
      throw InputError(path, line_of(node, 0), name,
                       "unknown table or key; a packing input has [packing] and [output]");
    if (!node.is_table()) throw InputError(path, line_of(node, 0), name, "a table [" + name + "]");
  }
  const auto* packing = root["packing"].as_table();
  if (!packing) throw InputError(path, 0, "packing", "a [packing] table");
  PackingInput input;
  input.source_path = path;
  input.params = packing_params_from_toml(*packing, path, "packing");
  if (const auto* out = root["output"].as_table()) {
    const Keys k(*out, path, "output", line_of(*out, 0), {"folder", "name", "vtu"});
    input.output_folder = k.string("folder", input.output_folder);
    input.output_name = k.string("name", input.output_name);
    input.write_vtu = k.boolean("vtu", input.write_vtu);
    if (input.output_folder.empty()) k.fail("folder", "a non-empty folder name");
    if (input.output_name.empty() || input.output_name.find_first_of("/\\") != std::string::npos ||
        input.output_name == "." || input.output_name == "..")
      k.fail("name", "a plain file name (no '/'), got \"" + input.output_name + "\"");
  }
  return input;
}

}  // namespace mpmcd::packing
