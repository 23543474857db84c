#pragma once
// A synthetic contact problem shared by the contact unit tests and bench_contact.
#include <cmath>
#include <numbers>
#include <random>

#include "mpmcd/contact/problem.hpp"

namespace mpmcd::test_support {

// A dense packing's problem in miniature: at each of `nodes` nodes three grain fields (slots)
// in mutual contact, the first also touching a wall; random masses, approach velocities, normals
// and friction. The grain-grain contacts come node by node, the wall contacts after all of them
// (as detection creates them), so a node's contacts are not contiguous.
inline contact::Problem<2> many_node_problem(int nodes) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  contact::Problem<2> p;
  p.dt = 1e-6;
  for (int n = 0; n < nodes; ++n)
    for (int k = 0; k < 3; ++k)
      p.slots.push_back({0.5 + u(rng), Vec<2>(u(rng) - 0.5, -u(rng)), k, 1000 + 7 * n});
  for (int n = 0; n < nodes; ++n)
    for (int a = 0; a < 3; ++a)
      for (int b = a + 1; b < 3; ++b) {
        contact::Contact<2> c;
        c.a = 3 * n + a;
        c.b = 3 * n + b;
        const double th = 2 * std::numbers::pi * u(rng);
        c.normal = Vec<2>(std::cos(th), std::sin(th));
        c.gap = 0.1 * p.dt * u(rng);
        c.friction = 0.3 * u(rng);
        p.contacts.push_back(c);
      }
  for (int n = 0; n < nodes; ++n) {
    contact::Contact<2> c;
    c.a = -1;
    c.b = 3 * n;
    c.normal = Vec<2>(0.0, 1.0);
    c.friction = 0.2;
    p.contacts.push_back(c);
  }
  return p;
}

}  // namespace mpmcd::test_support
