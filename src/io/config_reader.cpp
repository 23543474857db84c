// Reader of the simulation input (one TOML file, SI units): each table is checked against its
// schema (io/config.cpp) and its bound keys fill the matching section of io::Config
// (TableReader::fill); what follows here is only what a key's declaration cannot say: defaults
// that depend on other keys, file paths, and the checks across keys (grid size, grains inside the
// grid, material references, time-step bounds, ...). A key is named by the member it fills, so
// its name is written once, in the schema.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "law_keys.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/io/load_config.hpp"
#include "mpmcd/io/schema.hpp"
#include "mpmcd/materials/law.hpp"
#include "wall_reader.hpp"

namespace mpmcd::io {

namespace {

constexpr double kMaxNodes = 1e8;                     // largest grid accepted [-]
constexpr std::uintmax_t kMaxFileBytes = 16u << 20u;  // largest input file accepted [bytes]
constexpr const char* kAxes[] = {"x", "y", "z"};

std::string vec_text(const std::vector<double>& v) {
  std::string out = "[";
  for (std::size_t i = 0; i < v.size(); ++i) out += (i ? ", " : "") + number_text(v[i]);
  return out + "]";
}

/// Reads the whole input once the TOML is parsed.
class ConfigReader {
 public:
  ConfigReader(const toml::table& root, const std::string& source_name)
      : root_(root), schema_(config_schema()), source_(source_name) {
    ctx_.file = source_name;
    ctx_.schema = &schema_;
  }

  Config read() {
    Config c;
    TableReader r(root_, schema_.table(""), ctx_, "", 0);
    read_simulation(r, c);
    read_grid(r, c);
    read_materials(r, c);
    read_grains(r, c);
    read_boundaries(r, c);
    r.sub(&Config::loads).fill(c.loads);
    if (c.loads.gravity.empty()) c.loads.gravity.assign(dim_, 0.0);
    read_time(r, c);
    r.sub(&Config::solver).fill(c.solver);
    check_time_against_solver(r, c);
    read_contact(r, c);
    const WallReader walls{source_, dim_};
    walls.read_walls(r, c);
    walls.read_loading(r, c);
    walls.read_stop(r, c);
    r.sub(&Config::output).fill(c.output);
    r.sub(&Config::checkpoint).fill(c.checkpoint);
    return c;
  }

 private:
  void read_simulation(const TableReader& root, Config& c) {
    const TableReader r = root.sub(&Config::simulation);
    SimulationSection& s = c.simulation;
    r.fill(s);
    for (char ch : s.name)
      if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-' || ch == '.'))
        r.fail(&SimulationSection::name,
               fmt::format("expected letters, digits, '_', '-' or '.' only (it names "
                           "output files), got \"{}\"",
                           s.name));
    dim_ = static_cast<std::size_t>(s.dimension);
    ctx_.lengths = {{"Dim", dim_}, {"Dim*Dim", dim_ * dim_}};
  }

  void read_grid(const TableReader& root, Config& c) {
    const TableReader r = root.sub(&Config::grid);
    GridSection& g = c.grid;
    r.fill(g);
    double nodes = 1.0;
    for (std::size_t a = 0; a < dim_; ++a) nodes *= std::floor(g.extent[a] / g.cell_size) + 1.0;
    if (!(nodes <= kMaxNodes))
      r.fail(&GridSection::cell_size,
             fmt::format("the grid would have {:.3g} nodes, more than the limit of {:.0e}; use "
                         "larger cells or a smaller extent",
                         nodes, kMaxNodes));
    for (std::size_t a = 0; a < dim_; ++a) {
      const double n = g.extent[a] / g.cell_size;
      if (n < 2.0 - 1e-9)
        r.fail(&GridSection::extent,
               fmt::format("expected at least 2 cells along {} (extent >= 2 cell_size "
                           "= {} m), got {} m = {:.6g} cells",
                           kAxes[a], number_text(2 * g.cell_size), number_text(g.extent[a]), n));
      if (std::fabs(n - std::round(n)) > 1e-6 * std::max(1.0, n))
        r.fail(&GridSection::extent,
               fmt::format("expected a whole number of cells along {}: extent {} m / cell_size {} "
                           "m = {:.6g} cells",
                           kAxes[a], number_text(g.extent[a]), number_text(g.cell_size), n));
    }
  }

  void read_materials(const TableReader& root, Config& c) {
    const auto tables = root.tables(&Config::materials);
    // The law decides which other keys a table has, so it is checked first.
    const std::string& law_key =
        schema_.table(root.key(&Config::materials).table).find(&MaterialSection::law)->name;
    std::map<std::string, std::int64_t> seen;  // name -> line
    for (std::size_t i = 0; i < tables.size(); ++i) {
      const toml::table& t = *tables[i];
      const std::string law_path =
          root.element_path(root.name(&Config::materials), i) + "." + law_key;
      const toml::node* law_node = t.get(law_key);
      if (!law_node)
        throw InputError(source_, line_of(t), law_path,
                         "missing required key (one of " +
                             fmt::format("{}", fmt::join(law_names(), ", ")) + ")");
      const auto law = law_node->value_exact<std::string>();
      if (!law)
        throw InputError(source_, line_of(*law_node), law_path,
                         fmt::format("expected one of {}, got {}", fmt::join(law_names(), ", "),
                                     describe_node(*law_node)));
      std::vector<KeySpec> extra;
      for (const auto& info : materials::law_registry())
        if (info.name == *law) extra = law_keys(info);
      if (extra.empty()) {
        std::string msg = fmt::format("unknown law \"{}\", expected one of {}", *law,
                                      fmt::join(law_names(), ", "));
        if (const std::string near = nearest_name(*law, law_names()); !near.empty())
          msg += fmt::format(" (did you mean \"{}\"?)", near);
        throw InputError(source_, line_of(*law_node), law_path, msg);
      }
      const TableReader r = root.element(&Config::materials, i, t, extra);
      MaterialSection m;
      m.line = r.line();
      r.fill(m);
      for (const auto& k : extra) r.read(k.name, m.params[k.name]);
      if (auto [it, inserted] = seen.emplace(m.name, r.line(&MaterialSection::name)); !inserted)
        r.fail(&MaterialSection::name,
               fmt::format("duplicate material name \"{}\" (first defined on line {})", m.name,
                           it->second));
      c.materials.push_back(std::move(m));
    }
  }

  void read_grains(const TableReader& root, Config& c) {
    const auto tables = root.tables(&Config::grains);
    std::vector<std::string> names;
    for (const auto& m : c.materials) names.push_back(m.name);
    for (std::size_t i = 0; i < tables.size(); ++i) {
      const TableReader r = root.element(&Config::grains, i, *tables[i]);
      GrainSection g;
      g.line = r.line();
      r.fill(g);
      check_shape_dimension(r, g.shape);
      const bool lattice_only = g.shape == "rectangle" || g.shape == "sphere" || g.shape == "box" ||
                                (g.shape == "packing" && dim_ == 3);
      if (g.seeding.empty()) g.seeding = lattice_only ? "lattice" : "polar";
      if (lattice_only && g.seeding == "polar")
        r.fail(&GrainSection::seeding,
               fmt::format("polar seeding is for disks and packings of disks, not for shape "
                           "\"{}\"{}",
                           g.shape, dim_ == 3 ? " (3D grains are seeded on the lattice)" : ""));
      if (std::find(names.begin(), names.end(), g.material) == names.end()) {
        std::string msg =
            fmt::format("unknown material \"{}\", defined: {}", g.material, fmt::join(names, ", "));
        if (const std::string near = nearest_name(g.material, names); !near.empty())
          msg += fmt::format(" (did you mean \"{}\"?)", near);
        r.fail(&GrainSection::material, msg);
      }
      check_shape_keys(r, g.shape);
      if (g.shape == "disk" || g.shape == "sphere") {
        std::vector<double> lo(dim_), hi(dim_);
        for (std::size_t a = 0; a < dim_; ++a) {
          lo[a] = g.center[a] - g.radius;
          hi[a] = g.center[a] + g.radius;
        }
        check_inside_grid(r, c.grid,
                          fmt::format("{} (center {}, radius {} m)", g.shape, vec_text(g.center),
                                      number_text(g.radius)),
                          lo, hi);
      } else if (g.shape == "rectangle" || g.shape == "box") {
        for (std::size_t a = 0; a < dim_; ++a)
          if (!(g.min_corner[a] < g.max_corner[a]))
            r.fail(&GrainSection::max_corner,
                   fmt::format("expected max_corner > min_corner along {}, got {} <= {}", kAxes[a],
                               number_text(g.max_corner[a]), number_text(g.min_corner[a])));
        check_inside_grid(
            r, c.grid,
            fmt::format("{} {} to {}", g.shape, vec_text(g.min_corner), vec_text(g.max_corner)),
            g.min_corner, g.max_corner);
      } else {
        g.file = packing_path(r, g.file);
      }
      const TableReader iv = r.sub(&GrainSection::initial);
      iv.fill(g.initial);
      if (dim_ == 3 && g.initial.angular_velocity != 0.0)
        iv.fail(&InitialVelocity::angular_velocity,
                "a spin about e_z is 2D only; in 3D give a rigid rotation as the antisymmetric "
                "`gradient` (row-major 3 x 3)");
      auto zeros = [](std::vector<double>& v, std::size_t n) {
        if (v.empty()) v.assign(n, 0.0);
      };
      zeros(g.initial.velocity, dim_);
      zeros(g.initial.gradient, dim_ * dim_);
      zeros(g.initial.sine_amplitude, dim_);
      zeros(g.initial.sine_wavevector, dim_);
      c.grains.push_back(std::move(g));
    }
  }

  /// The packing file `file` of grain reader `r`, resolved against the input's folder; it must
  /// be a regular file.
  std::string packing_path(const TableReader& r, const std::string& file) const {
    const std::filesystem::path folder = std::filesystem::path(source_).parent_path();
    const std::filesystem::path path = (folder / file).lexically_normal();
    std::error_code ec;
    const auto st = std::filesystem::status(path, ec);
    if (std::filesystem::is_directory(st))
      r.fail(&GrainSection::file,
             fmt::format("a packing file (CSV) or packing input (TOML), but \"{}\" "
                         "(\"{}\", relative to the input file's folder) is a "
                         "directory",
                         file, path.string()));
    if (!std::filesystem::is_regular_file(st))
      r.fail(&GrainSection::file, fmt::format("packing file \"{}\" not found (looked for \"{}\", "
                                              "relative to the input file's folder)",
                                              file, path.string()));
    return path.string();
  }

  /// disk and rectangle are 2D shapes, sphere and box 3D ones; packing is either (its file says).
  void check_shape_dimension(const TableReader& r, const std::string& shape) const {
    static const std::map<std::string, std::pair<std::size_t, std::string>> shapes = {
        {"disk", {2, "sphere"}},
        {"rectangle", {2, "box"}},
        {"sphere", {3, "disk"}},
        {"box", {3, "rectangle"}}};
    const auto it = shapes.find(shape);
    if (it == shapes.end() || it->second.first == dim_) return;
    const auto& [dim, other] = it->second;
    r.fail(&GrainSection::shape, fmt::format("shape \"{}\" is {}D only, but [simulation] "
                                             "dimension = {}: use shape = \"{}\"",
                                             shape, dim, dim_, other));
  }

  /// Each shape has its keys: required for it, rejected for the others.
  void check_shape_keys(const TableReader& r, const std::string& shape) const {
    const std::vector<std::string> ball = {r.name(&GrainSection::center),
                                           r.name(&GrainSection::radius)};
    const std::vector<std::string> corners = {r.name(&GrainSection::min_corner),
                                              r.name(&GrainSection::max_corner)};
    const std::map<std::string, std::vector<std::string>> keys = {
        {"disk", ball},
        {"rectangle", corners},
        {"packing", {r.name(&GrainSection::file)}},
        {"sphere", ball},
        {"box", corners}};
    // Each key with its shape in this dimension, checked in the order of the 2D names.
    const std::string round = dim_ == 3 ? "sphere" : "disk", flat = dim_ == 3 ? "box" : "rectangle";
    const std::vector<std::pair<std::string, std::string>> owners = {
        {ball[0], round},
        {ball[1], round},
        {r.name(&GrainSection::file), "packing"},
        {corners[0], flat},
        {corners[1], flat}};
    const auto& mine = keys.at(shape);
    for (const auto& [k, owner] : owners) {
      const bool needed = std::find(mine.begin(), mine.end(), k) != mine.end();
      if (needed && !r.has(k))
        r.fail(k, fmt::format("missing required key for shape \"{}\"", shape));
      if (!needed && r.has(k))
        r.fail(k, fmt::format("key is only for shape \"{}\", not for shape \"{}\"", owner, shape));
    }
  }

  /// The box [lo, hi] must lie in the grid shrunk by one cell on every side.
  void check_inside_grid(const TableReader& r, const GridSection& g, const std::string& what,
                         const std::vector<double>& lo, const std::vector<double>& hi) const {
    const double tol = 1e-9 * g.cell_size;
    for (std::size_t a = 0; a < dim_; ++a) {
      const double min = g.origin[a] + g.cell_size;
      const double max = g.origin[a] + g.extent[a] - g.cell_size;
      if (lo[a] < min - tol || hi[a] > max + tol)
        r.fail_table(fmt::format(
            "{} must lie inside the grid with one cell of margin (ghost nodes): {} from {} to "
            "{} m allowed, but it spans {} to {} m",
            what, kAxes[a], number_text(min), number_text(max), number_text(lo[a]),
            number_text(hi[a])));
    }
  }

  void read_boundaries(const TableReader& root, Config& c) {
    const auto tables = root.tables(&Config::boundaries);
    for (std::size_t i = 0; i < tables.size(); ++i) {
      const TableReader r = root.element(&Config::boundaries, i, *tables[i]);
      BoundarySection b;
      b.line = r.line();
      r.fill(b);
      if (b.velocity.empty()) b.velocity.assign(dim_, 0.0);
      if (dim_ < 3 && (b.nodes == "zmin" || b.nodes == "zmax"))
        r.fail(&BoundarySection::nodes,
               fmt::format("\"{}\" exists only in 3D (dimension = 3)", b.nodes));
      for (const auto& f : b.fix)
        if (dim_ < 3 && f == "z")
          r.fail(&BoundarySection::fix, "component \"z\" exists only in 3D");
      if (b.nodes == "box") {
        if (!r.has(&BoundarySection::box_min))
          r.fail(&BoundarySection::box_min, "missing required key for nodes = \"box\"");
        if (!r.has(&BoundarySection::box_max))
          r.fail(&BoundarySection::box_max, "missing required key for nodes = \"box\"");
        const GridSection& g = c.grid;
        for (std::size_t a = 0; a < dim_; ++a) {
          if (!(b.box_min[a] < b.box_max[a]))
            r.fail(&BoundarySection::box_max,
                   fmt::format("expected box_max > box_min along {}, got {} <= {}", kAxes[a],
                               number_text(b.box_max[a]), number_text(b.box_min[a])));
          const double n = std::round(g.extent[a] / g.cell_size);
          const double first =
              std::max(0.0, std::ceil((b.box_min[a] - g.origin[a]) / g.cell_size - 1e-9));
          const double last =
              std::min(n, std::floor((b.box_max[a] - g.origin[a]) / g.cell_size + 1e-9));
          if (first > last)
            r.fail_table(fmt::format("the box {} to {} contains no grid node (along {})",
                                     vec_text(b.box_min), vec_text(b.box_max), kAxes[a]));
        }
      } else {
        for (const std::string& k :
             {r.name(&BoundarySection::box_min), r.name(&BoundarySection::box_max),
              r.name(&BoundarySection::moving)})
          if (r.has(k)) r.fail(k, "key is only for nodes = \"box\"");
      }
      c.boundaries.push_back(std::move(b));
    }
  }

  void read_time(const TableReader& root, Config& c) {
    const TableReader r = root.sub(&Config::time);
    TimeSection& t = c.time;
    r.fill(t);
    if (!r.has(&TimeSection::dt_min)) t.dt_min = t.dt / 1024.0;
    if (!(t.end_time >= t.dt))
      r.fail(&TimeSection::end_time, fmt::format("expected end_time >= dt = {} s, got {}",
                                                 number_text(t.dt), number_text(t.end_time)));
    if (!(t.dt_min <= t.dt))
      r.fail(&TimeSection::dt_min, fmt::format("expected 0 < dt_min <= dt = {} s, got {}",
                                               number_text(t.dt), number_text(t.dt_min)));
    if (t.control != "newton") {
      for (const std::string& k :
           {r.name(&TimeSection::dt_max), r.name(&TimeSection::target_iterations)})
        if (r.has(k)) r.fail(k, "key is only for control = \"newton\"");
    }
    if (!r.has(&TimeSection::dt_max)) t.dt_max = t.dt;
    if (!(t.dt_max >= t.dt))
      r.fail(&TimeSection::dt_max, fmt::format("expected dt_max >= dt = {} s, got {}",
                                               number_text(t.dt), number_text(t.dt_max)));
  }

  // Keys of [time] bounded by [solver] (read after it).
  void check_time_against_solver(const TableReader& root, const Config& c) {
    const TableReader r = root.sub(&Config::time);
    if (c.time.control == "newton" && !(c.time.target_iterations < c.solver.max_iterations))
      r.fail(&TimeSection::target_iterations,
             fmt::format("expected target_iterations < solver.max_iterations = {}, got {}",
                         c.solver.max_iterations, c.time.target_iterations));
  }

  void read_contact(const TableReader& root, Config& c) {
    const TableReader r = root.sub(&Config::contact);
    ContactSection& k = c.contact;
    r.fill(k);
    const auto tables = r.tables(&ContactSection::pairs);
    for (std::size_t i = 0; i < tables.size(); ++i) {
      const TableReader q = r.element(&ContactSection::pairs, i, *tables[i]);
      ContactPairSection pair;
      pair.line = q.line();
      q.fill(pair);
      if (pair.materials.size() != 2)
        q.fail(&ContactPairSection::materials,
               fmt::format("expected 2 material names, got {}", pair.materials.size()));
      for (const auto& m : pair.materials) {
        bool known = false;
        for (const auto& mat : c.materials) known = known || mat.name == m;
        if (!known)
          q.fail(&ContactPairSection::materials, fmt::format("unknown material \"{}\"", m));
      }
      k.pairs.push_back(std::move(pair));
    }
  }

  const toml::table& root_;
  const Schema& schema_;
  std::string source_;
  CheckContext ctx_;
  std::size_t dim_ = 2;
};

}  // namespace

Config parse_config(std::string_view text, const std::string& source_name) {
  if (text.find_first_not_of(" \t\r\n") == std::string_view::npos)
    throw InputError(source_name, 0, "",
                     "the file is empty; expected a TOML simulation input (see docs/input.md)");
  if (const auto nul = text.find('\0'); nul != std::string_view::npos) {
    const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<long>(nul), '\n');
    throw InputError(source_name, line, "", "binary data (a NUL byte): expected a TOML text file");
  }
  toml::table root;
  try {
    root = toml::parse(text, std::string_view(source_name));
  } catch (const toml::parse_error& e) {
    throw InputError(source_name, static_cast<std::int64_t>(e.source().begin.line), "",
                     fmt::format("TOML syntax error: {}", e.description()));
  }
  Config c = ConfigReader(root, source_name).read();
  c.source_path = source_name;
  c.source_text = std::string(text);
  return c;
}

Config load_config(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st))
    throw InputError(path, 0, "", "cannot read the input file: no such file");
  if (fs::is_directory(st))
    throw InputError(path, 0, "", "cannot read the input file: it is a directory");
  if (!fs::is_regular_file(st))
    throw InputError(path, 0, "", "cannot read the input file: not a regular file");
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw InputError(path, 0, "", "cannot read the input file: " + ec.message());
  if (size > kMaxFileBytes)
    throw InputError(path, 0, "",
                     fmt::format("the file is too large ({} bytes; an input file has at most {} "
                                 "bytes): is it really the TOML input?",
                                 size, kMaxFileBytes));
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw InputError(path, 0, "",
                     fmt::format("cannot read the input file: {}", std::strerror(errno)));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw InputError(path, 0, "", "cannot read the input file: read error");
  return parse_config(buffer.str(), path);
}

}  // namespace mpmcd::io
