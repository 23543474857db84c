// The default contact law "coulomb" (include/mpmcd/contact/law.hpp): Signorini non-penetration and
// Coulomb friction (method.md §4), its exact local solution (local_solution, declared in
// include/mpmcd/contact/problem.hpp) and its registry entry (coulomb_law). The model of a contact
// law's file (docs/architecture.md, "Adding a contact law").
#include <cmath>

#include "mpmcd/contact/law.hpp"
#include "mpmcd/contact/problem.hpp"

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

template Vec<2> local_solution<2>(const Vec<2>&, const Mat<2>&, const Vec<2>&, double, double);
template Vec<3> local_solution<3>(const Vec<3>&, const Mat<3>&, const Vec<3>&, double, double);

ContactLaw coulomb_law() {
  ContactLaw law;
  law.name = "coulomb";
  law.description =
      "Signorini + Coulomb (method.md §4): p_n >= 0, u_n + g/dt >= 0, p_n (u_n + g/dt) = 0; "
      "stick (u_t = 0) inside the cone |p_t| <= mu_f p_n, else slide on it against u_t";
  law.params = {"friction"};
  law.local_2d = &local_solution<2>;
  law.local_3d = &local_solution<3>;
  law.signorini = true;
  law.active_set = true;  // its frictionless contacts
  return law;
}

}  // namespace mpmcd::contact
