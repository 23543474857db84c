// A contact problem as text, to replay a step's problem outside a run (write_problem,
// read_problem; include/mpmcd/contact/problem.hpp): the contact law unless it is the default
// ("law <name>"), one line per slot and contact, each group's slots, their directions and the
// compliance on them (v2; v1 files, with each group's full Dim k x Dim k matrix, are read too), 17
// significant digits.
#include <fmt/format.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "mpmcd/contact/law.hpp"
#include "mpmcd/contact/problem.hpp"
#include "mpmcd/core/errors.hpp"

namespace mpmcd::contact {

template <int Dim>
void write_problem(const Problem<Dim>& p, const std::string& path) {
  std::ofstream out(path, std::ios::trunc);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << "# mpmcd contact problem v2\n" << fmt::format("dim {}\ndt {:.17g}\n", Dim, p.dt);
  if (p.law != Problem<Dim>{}.law) out << "law " << p.law << "\n";  // the default law: no line
  out << "slots " << p.slots.size() << "\n";
  for (const auto& s : p.slots) {
    out << fmt::format("{:.17g}", s.mass);
    for (int d = 0; d < Dim; ++d) out << fmt::format(" {:.17g}", s.v_free[d]);
    out << " " << s.grain << " " << s.node << " " << s.group << " " << s.local << "\n";
  }
  out << "contacts " << p.contacts.size() << "\n";
  for (const auto& c : p.contacts) {
    out << c.a << " " << c.b << " " << c.wall;
    for (int d = 0; d < Dim; ++d) out << fmt::format(" {:.17g}", c.normal[d]);
    for (int d = 0; d < Dim; ++d) out << fmt::format(" {:.17g}", c.wall_velocity[d]);
    out << fmt::format(" {:.17g} {:.17g}", c.gap, c.friction);
    for (int d = 0; d < Dim; ++d) out << fmt::format(" {:.17g}", c.impulse[d]);
    out << "\n";
  }
  out << "groups " << p.groups.size() << "\n";
  for (const auto& g : p.groups) {
    out << g.slots.size();
    for (auto sl : g.slots) out << " " << sl;
    out << "\n";
    // v2: per slot "rank" and its directions (rank columns of Dim numbers), then Gr's rows.
    for (std::size_t j = 0; j < g.slots.size(); ++j) {
      out << g.rank(j);
      for (int m = 0; m < g.rank(j); ++m)
        for (int d = 0; d < Dim; ++d) out << fmt::format(" {:.17g}", g.basis[j](d, m));
      out << "\n";
    }
    for (Eigen::Index i = 0; i < g.Gr.rows(); ++i) {
      for (Eigen::Index j = 0; j < g.Gr.cols(); ++j)
        out << fmt::format("{}{:.17g}", j ? " " : "", g.Gr(i, j));
      out << "\n";
    }
  }
}

template <int Dim>
Problem<Dim> read_problem(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "", "cannot open the contact problem file");
  Problem<Dim> p;
  std::string line;
  std::int64_t lineno = 0;
  int version = 1;  // from the header comment "# mpmcd contact problem v<N>"
  auto next = [&](const char* what) -> std::istringstream {
    while (std::getline(in, line)) {
      ++lineno;
      if (line.rfind("# mpmcd contact problem v2", 0) == 0) version = 2;
      if (!line.empty() && line[0] != '#') return std::istringstream(line);
    }
    throw InputError(path, lineno, what, "unexpected end of file");
  };
  auto expect = [&](std::istringstream& ss, const char* key) {
    std::string k;
    ss >> k;
    if (k != key)
      throw InputError(path, lineno, key, "expected the line '" + std::string(key) + " ...'");
  };
  auto check = [&](std::istringstream& ss, const char* what) {
    if (ss.fail()) throw InputError(path, lineno, what, "malformed numbers");
  };
  {
    auto ss = next("dim");
    expect(ss, "dim");
    int dim = 0;
    ss >> dim;
    if (dim != Dim) throw InputError(path, lineno, "dim", fmt::format("expected {}", Dim));
  }
  {
    auto ss = next("dt");
    expect(ss, "dt");
    ss >> p.dt;
    check(ss, "dt");
    if (!(p.dt > 0)) throw InputError(path, lineno, "dt", "expected dt > 0");
  }
  // "<key> <count>" lines; a count beyond 1e8 is a corrupt file, not a problem to allocate.
  const auto count_in = [&](std::istringstream& ss, const char* key) {
    expect(ss, key);
    std::size_t n = 0;
    ss >> n;
    check(ss, key);
    if (n > 100000000) throw InputError(path, lineno, key, "count above 1e8: corrupt file");
    return n;
  };
  const auto count = [&](const char* key) {
    auto ss = next(key);
    return count_in(ss, key);
  };
  {
    // An optional "law <name>" line (none: the default law), then the slots.
    auto ss = next("slots");
    if (ss.str().rfind("law ", 0) == 0) {
      std::string key;
      ss >> key >> p.law;
      std::string known;
      bool registered = false;
      for (const auto& name : contact_law_names()) {
        known += (known.empty() ? "" : ", ") + name;
        registered = registered || name == p.law;
      }
      if (!registered)
        throw InputError(
            path, lineno, "law",
            fmt::format("unknown contact law '{}', expected one of: {}", p.law, known));
      ss = next("slots");
    }
    p.slots.resize(count_in(ss, "slots"));
  }
  for (auto& s : p.slots) {
    auto ss = next("slot");
    ss >> s.mass;
    for (int d = 0; d < Dim; ++d) ss >> s.v_free[d];
    ss >> s.grain >> s.node >> s.group >> s.local;
    check(ss, "slot");
    if (!(s.mass > 0)) throw InputError(path, lineno, "slot", "expected a mass > 0");
  }
  p.contacts.resize(count("contacts"));
  for (auto& c : p.contacts) {
    auto ss = next("contact");
    ss >> c.a >> c.b >> c.wall;
    for (int d = 0; d < Dim; ++d) ss >> c.normal[d];
    for (int d = 0; d < Dim; ++d) ss >> c.wall_velocity[d];
    ss >> c.gap >> c.friction;
    for (int d = 0; d < Dim; ++d) ss >> c.impulse[d];
    check(ss, "contact");
    const auto ns = static_cast<std::int32_t>(p.slots.size());
    if (c.b < 0 || c.b >= ns || c.a >= ns || c.a < -1)
      throw InputError(path, lineno, "contact", "slot index out of range");
  }
  p.groups.resize(count("groups"));
  for (auto& g : p.groups) {
    auto ss = next("group");
    std::size_t k = 0;
    ss >> k;
    if (k > p.slots.size())
      throw InputError(path, lineno, "group", "more slots than the problem has");
    g.slots.resize(k);
    for (auto& sl : g.slots) ss >> sl;
    check(ss, "group");
    for (auto sl : g.slots)
      if (sl < 0 || sl >= static_cast<std::int32_t>(p.slots.size()))
        throw InputError(path, lineno, "group", "slot index out of range");
    if (version == 1) {  // the full Dim k x Dim k compliance
      Eigen::MatrixXd G(static_cast<Eigen::Index>(Dim * k), static_cast<Eigen::Index>(Dim * k));
      for (Eigen::Index i = 0; i < G.rows(); ++i) {
        auto row = next("group matrix");
        for (Eigen::Index j = 0; j < G.cols(); ++j) row >> G(i, j);
        check(row, "group matrix");
      }
      g.set_full(G);
      continue;
    }
    g.basis.assign(k, Mat<Dim>::Zero());
    g.col.assign(k + 1, 0);
    for (std::size_t j = 0; j < k; ++j) {
      auto row = next("group directions");
      int r = 0;
      row >> r;
      if (r < 1 || r > Dim)
        throw InputError(path, lineno, "group directions",
                         fmt::format("expected a rank in [1, {}]", Dim));
      for (int m = 0; m < r; ++m)
        for (int d = 0; d < Dim; ++d) row >> g.basis[j](d, m);
      check(row, "group directions");
      g.col[j + 1] = g.col[j] + r;
    }
    g.Gr.resize(g.col[k], g.col[k]);
    for (Eigen::Index i = 0; i < g.Gr.rows(); ++i) {
      auto row = next("group matrix");
      for (Eigen::Index j = 0; j < g.Gr.cols(); ++j) row >> g.Gr(i, j);
      check(row, "group matrix");
    }
  }
  for (const auto& s : p.slots)
    if (s.group >= static_cast<std::int32_t>(p.groups.size()) ||
        (s.group >= 0 &&
         (s.local < 0 || s.local >= static_cast<std::int32_t>(p.groups[s.group].slots.size()))))
      throw InputError(path, 0, "slot", "group index out of range");
  return p;
}

#define MPMCD_INSTANTIATE(D)                                             \
  template void write_problem<D>(const Problem<D>&, const std::string&); \
  template Problem<D> read_problem<D>(const std::string&);
MPMCD_INSTANTIATE(2)
MPMCD_INSTANTIATE(3)
#undef MPMCD_INSTANTIATE

}  // namespace mpmcd::contact
