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
    // 3D, exact for any symmetric positive-definite W (before 2026-11-26: W approximated by
    // tr(W)/3 I, which made Gauss-Seidel converge to wrong impulses with the grain compliance).
    // Stick: u_free + (g/dt) n + W P = 0, kept inside the cone |P_t| <= mu p_n. Slide:
    // P = p_n (n - mu s) with s the unit direction of the tangential velocity it leaves, found by
    // a damped fixed point from the stick direction; p_n from the normal condition.
    const double wnn = n.dot(W * n);
    if (mu > 0.0) {
      const Vec<Dim> P = -W.ldlt().solve(u_free + gap_over_dt * n);
      const double pn = P.dot(n);
      const Vec<Dim> pt = P - pn * n;
      if (pn > 0.0 && pt.norm() <= mu * pn) return P;
      const Vec<Dim> ut0 = u_free - u_free.dot(n) * n;
      Vec<Dim> s = pt.norm() > 0.0    ? Vec<Dim>(-pt / pt.norm())
                   : ut0.norm() > 0.0 ? Vec<Dim>(ut0 / ut0.norm())
                                      : Vec<Dim>::Zero();
      for (int k = 0; k < 100 && !s.isZero(); ++k) {
        const Vec<Dim> dir = n - mu * s;
        const double d = n.dot(W * dir);
        if (!(d > 0.0)) break;
        const double p = -un0 / d;
        const Vec<Dim> u = u_free + p * (W * dir);
        const Vec<Dim> ut = u - u.dot(n) * n;
        if (ut.norm() == 0.0) return p * dir;
        const Vec<Dim> s_new = ut / ut.norm();
        if ((s_new - s).norm() < 1e-14) return p * (n - mu * s_new);
        s = (s + s_new).normalized();
      }
      if (!s.isZero()) {
        const double d = n.dot(W * (n - mu * s));
        if (d > 0.0) return (-un0 / d) * (n - mu * s);
      }
    }
    return (-un0 / wnn) * n;  // frictionless (or degenerate): the normal impulse alone
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
