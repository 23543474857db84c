// Reader of the input's walls, their loading and the stop criteria (io::load_config; the rest of
// the input in config_reader.cpp): each table filled through its schema, then the checks across
// keys (unique wall names, unit normals, a box where the observables need one, stage walls
// and until conditions naming walls that exist).
#include "wall_reader.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cctype>
#include <cmath>

#include "mpmcd/core/errors.hpp"

namespace mpmcd::io {

void WallReader::read_walls(const TableReader& root, Config& c) const {
  const auto tables = root.tables(&Config::walls);
  for (std::size_t i = 0; i < tables.size(); ++i) {
    const TableReader r = root.element(&Config::walls, i, *tables[i]);
    WallSection w;
    w.line = r.line();
    r.fill(w);
    if (w.velocity.empty()) w.velocity.assign(dim, 0.0);
    for (char ch : w.name)
      if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '_' && ch != '-')
        r.fail(&WallSection::name,
               fmt::format("\"{}\": only letters, digits, '_' and '-'", w.name));
    for (const auto& other : c.walls)
      if (other.name == w.name)
        r.fail(&WallSection::name, fmt::format("duplicate wall name \"{}\"", w.name));
    double len = 0;
    for (double x : w.normal) len += x * x;
    len = std::sqrt(len);
    if (!(len > 0)) r.fail(&WallSection::normal, "expected a non-zero normal");
    for (double& x : w.normal) x /= len;
    c.walls.push_back(std::move(w));
  }
}

/// The walls form a box: exactly 2 Dim, with normals +x, -x, +y, -y (and +z, -z in 3D;
/// analysis::find_box).
bool WallReader::walls_form_box(const std::vector<WallSection>& walls) const {
  int axes[6] = {0, 0, 0, 0, 0, 0};  // +x, -x, +y, -y, +z, -z
  for (const auto& w : walls)
    for (std::size_t k = 0; k < 2 * dim; ++k) {
      bool match = true;
      for (std::size_t a = 0; a < dim; ++a) {
        const double n = a == k / 2 ? (k % 2 == 0 ? 1.0 : -1.0) : 0.0;
        match = match && std::fabs(w.normal[a] - n) <= 1e-12;
      }
      if (match) ++axes[k];
    }
  bool box = walls.size() == 2 * dim;
  for (std::size_t k = 0; k < 2 * dim; ++k) box = box && axes[k] == 1;
  return box;
}

/// "four [[walls]] forming a box (normals +x, -x, +y, -y" (six and ±z in 3D), for messages.
std::string WallReader::box_words() const {
  return dim == 3 ? "six [[walls]] forming a box (normals +x, -x, +y, -y, +z, -z"
                  : "four [[walls]] forming a box (normals +x, -x, +y, -y";
}

/// The wall named `name` (its index), or an error at `key` of `r` naming the walls defined.
template <class S, class M>
std::size_t WallReader::wall_index(const TableReader& r, M S::*key, const std::string& name,
                                   const Config& c) {
  std::vector<std::string> names;
  for (std::size_t k = 0; k < c.walls.size(); ++k) {
    if (c.walls[k].name == name) return k;
    names.push_back(c.walls[k].name);
  }
  std::string msg = names.empty()
                        ? fmt::format("unknown wall \"{}\": the input has no [[walls]]", name)
                        : fmt::format(
                              "unknown wall \"{}\", expected the name of a [[walls]] "
                              "entry: {}",
                              name, fmt::join(names, ", "));
  if (const std::string near = nearest_name(name, names); !near.empty())
    msg += fmt::format(" (did you mean \"{}\"?)", near);
  r.fail(key, msg);
}

void WallReader::read_loading(const TableReader& root, Config& c) const {
  if (!root.has(&Config::loading)) return;
  const TableReader r = root.sub(&Config::loading);
  LoadingSection& l = c.loading;
  l.present = true;
  l.line = r.line();
  r.fill(l);
  const bool box = walls_form_box(c.walls);
  // The stages give every wall motion: a constant wall velocity besides them is refused.
  for (std::size_t k = 0; k < c.walls.size(); ++k)
    for (double v : c.walls[k].velocity)
      if (v != 0.0)
        throw InputError(source, c.walls[k].line, fmt::format("walls[{}].velocity", k),
                         fmt::format("expected no velocity (or zeros) for wall \"{}\" when "
                                     "[loading] is given: its stages move the walls (set it "
                                     "in [[loading.stages.walls]])",
                                     c.walls[k].name));
  const auto tables = r.tables(&LoadingSection::stages);
  for (std::size_t i = 0; i < tables.size(); ++i) {
    const TableReader q = r.element(&LoadingSection::stages, i, *tables[i]);
    StageSection st;
    st.line = q.line();
    q.fill(st);
    if (st.name.empty()) st.name = fmt::format("stage {}", i + 1);
    st.has_until = q.has(&StageSection::until);
    {
      const TableReader u = q.sub(&StageSection::until);
      StageUntilSection& un = st.until;
      un.line = u.line();
      u.fill(un);
      un.has_strain = u.has(&StageUntilSection::strain);
      un.has_stress = u.has(&StageUntilSection::stress);
      const bool any = u.has(&StageUntilSection::time) || u.has(&StageUntilSection::phi) ||
                       un.has_strain || un.has_stress;
      if (st.has_until && !any)
        u.fail_table("expected at least one end condition: time, phi, strain or stress");
      if (un.has_stress && !u.has(&StageUntilSection::wall))
        u.fail(&StageUntilSection::wall,
               "missing required key with `stress`: the name of the wall whose stress ends "
               "the stage");
      if (!un.has_stress && u.has(&StageUntilSection::wall))
        u.fail(&StageUntilSection::wall, "key is only for `stress`, which is not given");
      if (un.has_stress) (void)wall_index(u, &StageUntilSection::wall, un.wall, c);
      if (!box && (u.has(&StageUntilSection::phi) || un.has_strain || un.has_stress))
        u.fail_table(fmt::format("phi, strain and stress need {}), got {} walls", box_words(),
                                 c.walls.size()));
    }
    const auto wall_tables = q.tables(&StageSection::walls);
    std::vector<std::size_t> seen;
    for (std::size_t j = 0; j < wall_tables.size(); ++j) {
      const TableReader w = q.element(&StageSection::walls, j, *wall_tables[j]);
      StageWallSection sw;
      sw.line = w.line();
      w.fill(sw);
      sw.has_stress = w.has(&StageWallSection::stress);
      const std::size_t k = wall_index(w, &StageWallSection::name, sw.name, c);
      if (std::find(seen.begin(), seen.end(), k) != seen.end())
        w.fail(&StageWallSection::name,
               fmt::format("wall \"{}\" is listed twice in this stage", sw.name));
      seen.push_back(k);
      if (sw.velocity.empty() && !sw.has_stress)
        w.fail_table(fmt::format("expected `velocity` or `stress` for wall \"{}\"", sw.name));
      if (sw.has_stress) {
        if (!box)
          w.fail(&StageWallSection::stress,
                 fmt::format("a stress-controlled wall must be one of {}: its stress is its "
                             "force over its {} between its neighbours), got {} walls",
                             box_words(), dim == 3 ? "area" : "length", c.walls.size()));
        double vn = 0;
        for (std::size_t a = 0; a < sw.velocity.size(); ++a)
          vn += sw.velocity[a] * c.walls[k].normal[a];
        if (std::fabs(vn) > 0.0)
          w.fail(&StageWallSection::velocity,
                 fmt::format("both `velocity` and `stress` act along the normal of wall "
                             "\"{}\" (velocity . normal = {} m/s): with `stress`, "
                             "`velocity` may only slide along the wall (normal component 0)",
                             sw.name, number_text(vn)));
      }
      st.walls.push_back(std::move(sw));
    }
    l.stages.push_back(std::move(st));
  }
  for (std::size_t i = 0; i + 1 < l.stages.size(); ++i)
    if (!l.stages[i].has_until)
      r.element(&LoadingSection::stages, i, *tables[i])
          .fail_table(fmt::format("stage {} (\"{}\") has no end condition (`until`) but stage "
                                  "{} follows it: only the last stage may run to end_time",
                                  i + 1, l.stages[i].name, i + 2));
}

void WallReader::read_stop(const TableReader& root, Config& c) const {
  const TableReader r = root.sub(&Config::stop);
  StopSection& s = c.stop;
  s.line = r.line();
  r.fill(s);
  if (!walls_form_box(c.walls) && (s.phi > 0 || s.strain > 0 || s.stress > 0))
    r.fail_table(fmt::format("stop criteria need {}), got {} walls", box_words(), c.walls.size()));
}

}  // namespace mpmcd::io
