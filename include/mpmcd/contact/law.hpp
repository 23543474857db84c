#pragma once
/// The contact-law registry (docs/architecture.md, "Adding a contact law"): a contact law is the
/// local problem of one contact, u = u_free + W P with the law's relation between the relative
/// velocity u and the impulse P, solved exactly by a plain function (LocalSolver). The Gauss-Seidel
/// sweeps and their error measure call the law of the problem (Problem::law), resolved once per
/// solve; the default law "coulomb" is Signorini + Coulomb (local_solution, method.md §4).
#include <string>
#include <vector>

#include "mpmcd/core/types.hpp"

namespace mpmcd::contact {

/// Exact solution P [N s] of one contact's local problem u = u_free + W P: u_free the relative
/// velocity of B with respect to A without the contact's impulse [m/s], W the SPD Delassus block
/// [s/kg], n the unit normal from A to B, gap_over_dt = g/dt (A and B may approach by g this step)
/// [m/s], mu the contact's Coulomb coefficient (Contact::friction) [-].
template <int Dim>
using LocalSolver = Vec<Dim> (*)(const Vec<Dim>& u_free, const Mat<Dim>& W, const Vec<Dim>& n,
                                 double gap_over_dt, double mu);

/// One contact law: its name, what it reads of a contact and its local solver.
struct ContactLaw {
  std::string name;         ///< registry name, the input's `[contact] law`, e.g. "coulomb"
  std::string description;  ///< one line, with the relation it imposes
  /// The per-contact coefficients it reads: "friction" (Contact::friction, from `[contact]
  /// friction`, `[[contact.pairs]]` and the walls' `friction`) or none. An input that gives a
  /// coefficient the law does not read is refused.
  std::vector<std::string> params;
  LocalSolver<2> local_2d = nullptr;  ///< the 2D local solver
  LocalSolver<3> local_3d = nullptr;  ///< the 3D local solver
  /// Its frictionless contacts (mu = 0) obey the Signorini law p_n >= 0, u_n + g/dt >= 0,
  /// complementary, with no tangential impulse: the sweeps may then solve a node's frictionless
  /// contacts together (GsSettings::node_blocks) and over-relax them (GsSettings::relaxation).
  bool signorini = false;
  /// The active-set solver (solve_active_set: the normal impulses' complementarity problem)
  /// solves it, for frictionless contacts: the frictionless Signorini law only.
  bool active_set = false;

  /// The local solver in dimension Dim.
  template <int Dim>
  LocalSolver<Dim> local() const {
    if constexpr (Dim == 2)
      return local_2d;
    else
      return local_3d;
  }
  /// Whether it reads the per-contact coefficient `param` (e.g. "friction").
  bool reads(const std::string& param) const;
};

/// The built-in laws' entries (one file each, src/contact/<law>.cpp): Signorini + Coulomb.
ContactLaw coulomb_law();

/// The registered contact laws: the built-in ones in documentation order ("coulomb" first), then
/// those added by register_contact_law.
const std::vector<ContactLaw>& contact_law_registry();

/// The names of the registered contact laws, in registry order.
std::vector<std::string> contact_law_names();

/// The law registered as `name`; throws InputError (key "contact.law") listing the registered
/// laws if there is none.
const ContactLaw& find_contact_law(const std::string& name);

/// Adds `law` to the registry (a test's or a tool's own law); call it before the first input is
/// read (the input schema lists the laws once) and before any solve. Throws
/// std::invalid_argument if the name is taken or a local solver is missing.
void register_contact_law(ContactLaw law);

}  // namespace mpmcd::contact
