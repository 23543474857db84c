#pragma once
// A test-only contact law (docs/architecture.md, "Adding a contact law"): a bilateral contact, no
// separation and no friction. Registered by test_contact_law_recipe.cpp (the sweeps, the error
// measure, the active-set solver and the problem file use it) and by
// tests/unit/app/test_contact_law_in_app.cpp (the input and the run's settings).
#include "mpmcd/contact/law.hpp"

namespace mpmcd::test {

/// The law's local solver: the contact stays closed, u_n + g/dt = 0 (the normal impulse may
/// pull), with no tangential impulse: p = -(u_free.n + g/dt) / (n.W n) n. mu is not read.
template <int Dim>
Vec<Dim> bilateral_solution(const Vec<Dim>& u_free, const Mat<Dim>& W, const Vec<Dim>& n,
                            double gap_over_dt, double /*mu*/) {
  return (-(u_free.dot(n) + gap_over_dt) / n.dot(W * n)) * n;
}

/// Its registry entry, "test_bilateral".
inline contact::ContactLaw bilateral_contact_law() {
  contact::ContactLaw law;
  law.name = "test_bilateral";
  law.description = "no separation, no friction: u_n + g/dt = 0, p_t = 0 (test only)";
  law.params = {};  // reads no friction
  law.local_2d = &bilateral_solution<2>;
  law.local_3d = &bilateral_solution<3>;
  law.signorini = false;   // p_n < 0 is allowed: no nodal Signorini blocks, no over-relaxation
  law.active_set = false;  // the pivoting solves the Signorini law only
  return law;
}

}  // namespace mpmcd::test
