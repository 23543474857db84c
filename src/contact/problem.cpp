#include "mpmcd/contact/problem.hpp"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "mpmcd/core/errors.hpp"

namespace mpmcd::contact {

template <int Dim>
Vec<Dim> local_solution(const Vec<Dim>& u_free, double w, const Vec<Dim>& n, double gap_over_dt,
                        double mu) {
  // Signorini: p_n >= 0, u_n + g/dt >= 0, complementary; u = u_free + w P (method.md §4).
  const double un = u_free.dot(n);
  const double pn = -(un + gap_over_dt) / w;
  if (!(pn > 0.0)) return Vec<Dim>::Zero();  // open
  // Coulomb: stick (u_t = 0) inside the cone |p_t| <= mu p_n, else slide against u_t.
  const Vec<Dim> ut = u_free - un * n;
  const Vec<Dim> pt_stick = -ut / w;
  const double pt_norm = pt_stick.norm();
  if (pt_norm <= mu * pn) return pn * n + pt_stick;
  return pn * n + (mu * pn / pt_norm) * pt_stick;
}

namespace {

template <int Dim>
std::vector<Vec<Dim>> slot_velocities(const Problem<Dim>& p) {
  std::vector<Vec<Dim>> v(p.slots.size());
  for (std::size_t s = 0; s < p.slots.size(); ++s) v[s] = p.slots[s].v_free;
  for (const auto& c : p.contacts) {
    v[c.b] += c.impulse / p.slots[c.b].mass;
    if (c.a >= 0) v[c.a] -= c.impulse / p.slots[c.a].mass;
  }
  return v;
}

// Relative free velocity of contact c (its own impulse removed) and its Delassus coefficient w.
template <int Dim>
void free_velocity(const Problem<Dim>& p, const std::vector<Vec<Dim>>& v, const Contact<Dim>& c,
                   Vec<Dim>& u_free, double& w) {
  const double mb = p.slots[c.b].mass;
  const Vec<Dim> vb = v[c.b] - c.impulse / mb;
  w = 1.0 / mb;
  Vec<Dim> va = c.wall_velocity;
  if (c.a >= 0) {
    const double ma = p.slots[c.a].mass;
    va = v[c.a] + c.impulse / ma;
    w += 1.0 / ma;
  }
  u_free = vb - va;
}

}  // namespace

template <int Dim>
double error(const Problem<Dim>& p) {
  const auto v = slot_velocities(p);
  double num = 0, den = 0;
  for (const auto& c : p.contacts) {
    Vec<Dim> u;
    double w;
    free_velocity(p, v, c, u, w);
    const Vec<Dim> loc = local_solution<Dim>(u, w, c.normal, c.gap / p.dt, c.friction);
    num += (loc - c.impulse).squaredNorm();
    den += c.impulse.squaredNorm();
  }
  if (num == 0.0) return 0.0;
  return std::sqrt(num) / std::sqrt(std::max(den, 1e-300));
}

template <int Dim>
GsResult solve_gauss_seidel(Problem<Dim>& p, const GsSettings& settings) {
  GsResult r;
  r.error = error(p);
  if (p.contacts.empty() || r.error <= settings.tolerance) {
    r.converged = true;
    return r;
  }
  auto v = slot_velocities(p);
  while (r.sweeps < settings.max_sweeps) {
    for (auto& c : p.contacts) {
      Vec<Dim> u;
      double w;
      free_velocity(p, v, c, u, w);
      const Vec<Dim> P = local_solution<Dim>(u, w, c.normal, c.gap / p.dt, c.friction);
      const Vec<Dim> dP = P - c.impulse;
      v[c.b] += dP / p.slots[c.b].mass;
      if (c.a >= 0) v[c.a] -= dP / p.slots[c.a].mass;
      c.impulse = P;
    }
    ++r.sweeps;
    r.error = error(p);
    if (r.error <= settings.tolerance) {
      r.converged = true;
      break;
    }
  }
  return r;
}

template <int Dim>
void write_problem(const Problem<Dim>& p, const std::string& path) {
  std::ofstream out(path, std::ios::trunc);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << "# mpmcd contact problem v1\n" << fmt::format("dim {}\ndt {:.17g}\n", Dim, p.dt);
  out << "slots " << p.slots.size() << "\n";
  for (const auto& s : p.slots) {
    out << fmt::format("{:.17g}", s.mass);
    for (int d = 0; d < Dim; ++d) out << fmt::format(" {:.17g}", s.v_free[d]);
    out << " " << s.grain << " " << s.node << "\n";
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
}

template <int Dim>
Problem<Dim> read_problem(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "", "cannot open the contact problem file");
  Problem<Dim> p;
  std::string line;
  std::int64_t lineno = 0;
  auto next = [&](const char* what) -> std::istringstream {
    while (std::getline(in, line)) {
      ++lineno;
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
  std::size_t n = 0;
  {
    auto ss = next("slots");
    expect(ss, "slots");
    ss >> n;
    check(ss, "slots");
  }
  p.slots.resize(n);
  for (auto& s : p.slots) {
    auto ss = next("slot");
    ss >> s.mass;
    for (int d = 0; d < Dim; ++d) ss >> s.v_free[d];
    ss >> s.grain >> s.node;
    check(ss, "slot");
    if (!(s.mass > 0)) throw InputError(path, lineno, "slot", "expected a mass > 0");
  }
  {
    auto ss = next("contacts");
    expect(ss, "contacts");
    ss >> n;
    check(ss, "contacts");
  }
  p.contacts.resize(n);
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
  return p;
}

#define MPMCD_INSTANTIATE(D)                                                               \
  template Vec<D> local_solution<D>(const Vec<D>&, double, const Vec<D>&, double, double); \
  template double error<D>(const Problem<D>&);                                             \
  template GsResult solve_gauss_seidel<D>(Problem<D>&, const GsSettings&);                 \
  template void write_problem<D>(const Problem<D>&, const std::string&);                   \
  template Problem<D> read_problem<D>(const std::string&);
MPMCD_INSTANTIATE(2)
MPMCD_INSTANTIATE(3)
#undef MPMCD_INSTANTIATE

}  // namespace mpmcd::contact
