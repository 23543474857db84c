#pragma once
// One solver step with the app's retry rule, shared by the verification drivers.
#include <cstdint>

#include "mpmcd/mpm/solver.hpp"

namespace mpmcd::test_support {

// Solves one step of `dt` [s] from time t [s], halving dt after each retryable failure, at most
// `max_cuts` times; `dt` returns the step taken and `cuts` is increased by the halvings. The
// caller commits a converged step.
template <int Dim>
mpm::StepStats step_with_cuts(mpm::ImplicitSolver<Dim>& solver, double t, double& dt, int max_cuts,
                              std::int64_t& cuts) {
  mpm::StepStats st;
  for (int k = 0;; ++k) {
    solver.set_time(t);
    st = solver.solve_step(dt);
    if (st.converged || !st.retryable || k == max_cuts) return st;
    dt *= 0.5;
    ++cuts;
  }
}

}  // namespace mpmcd::test_support
