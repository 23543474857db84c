// The contact problem's own functions (include/mpmcd/contact/problem.hpp): the exact local
// Signorini-Coulomb solution of one contact (local_solution) and the net impulse on each slot
// (net_impulses). The Gauss-Seidel solver is in gauss_seidel.cpp, the problem's text file in
// problem_file.cpp.
#include "mpmcd/contact/problem.hpp"

#include <cmath>

namespace mpmcd::contact {

template <int Dim>
Vec<Dim> local_solution(const Vec<Dim>& u_free, const Mat<Dim>& W, const Vec<Dim>& n,
                        double gap_over_dt, double mu) {
  // Signorini: p_n >= 0, u_n + g/dt >= 0, complementary; u = u_free + W P (method.md §4).
  const double un0 = u_free.dot(n) + gap_over_dt;
  if (!(un0 < 0.0)) return Vec<Dim>::Zero();  // open: no impulse needed
  if constexpr (Dim == 2) {
    // Frame (n, t): stick solves W' (p_n, p_t) = -(u_n + g/dt, u_t); slide puts p_t = -s mu p_n
    // with s the sign of the resulting sliding velocity.
    const Vec<2> t(-n[1], n[0]);
    const double wnn = n.dot(W * n), wnt = n.dot(W * t), wtn = t.dot(W * n), wtt = t.dot(W * t);
    const double uft = u_free.dot(t);
    const double det = wnn * wtt - wnt * wtn;
    const double pn_stick = (-un0 * wtt + uft * wnt) / det;
    const double pt_stick = (-uft * wnn + un0 * wtn) / det;
    if (pn_stick > 0.0 && std::abs(pt_stick) <= mu * pn_stick) return pn_stick * n + pt_stick * t;
    for (double sgn : {1.0, -1.0}) {
      const double pn = -un0 / (wnn - sgn * mu * wnt);
      if (!(pn > 0.0)) continue;
      const double ut = uft + wtn * pn - wtt * sgn * mu * pn;
      if (sgn * ut >= 0.0) return pn * n - sgn * mu * pn * t;
    }
    return (-un0 / wnn) * n;  // degenerate W: frictionless normal impulse
  } else {
    // 3D: isotropic approximation w = tr(W)/3 (exact for lumped W = w I).
    const double w = W.trace() / Dim;
    const double pn = -un0 / w;
    const Vec<Dim> ut = u_free - u_free.dot(n) * n;
    const Vec<Dim> pt_stick = -ut / w;
    const double pt_norm = pt_stick.norm();
    if (pt_norm <= mu * pn) return pn * n + pt_stick;
    return pn * n + (mu * pn / pt_norm) * pt_stick;
  }
}

// Net impulse on each slot: sum of the impulses of the contacts where it is B, minus where it is A.
template <int Dim>
std::vector<Vec<Dim>> net_impulses(const Problem<Dim>& p) {
  std::vector<Vec<Dim>> net(p.slots.size(), Vec<Dim>::Zero());
  for (const auto& c : p.contacts) {
    net[c.b] += c.impulse;
    if (c.a >= 0) net[c.a] -= c.impulse;
  }
  return net;
}

#define MPMCD_INSTANTIATE(D)                                                                      \
  template Vec<D> local_solution<D>(const Vec<D>&, const Mat<D>&, const Vec<D>&, double, double); \
  template std::vector<Vec<D>> net_impulses<D>(const Problem<D>&);
MPMCD_INSTANTIATE(2)
MPMCD_INSTANTIATE(3)
#undef MPMCD_INSTANTIATE

}  // namespace mpmcd::contact
