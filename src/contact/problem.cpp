// The contact problem's own functions (include/mpmcd/contact/problem.hpp): the net impulse on each
// slot (net_impulses). The local Signorini-Coulomb solution of one contact (local_solution) is the
// default contact law's, in coulomb.cpp; the Gauss-Seidel solver is in gauss_seidel.cpp, the
// problem's text file in problem_file.cpp.
#include "mpmcd/contact/problem.hpp"

namespace mpmcd::contact {

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

#define MPMCD_INSTANTIATE(D) template std::vector<Vec<D>> net_impulses<D>(const Problem<D>&);
MPMCD_INSTANTIATE(2)
MPMCD_INSTANTIATE(3)
#undef MPMCD_INSTANTIATE

}  // namespace mpmcd::contact
