// mpmcd command line: all logic lives in the app module (src/app/cli.cpp).
#include "mpmcd/app/cli.hpp"
#include "mpmcd/core/allocator.hpp"
#include "mpmcd/core/openmp_env.hpp"
#include "mpmcd/parallel/comm.hpp"

int main(int argc, char** argv) {
  mpmcd::apply_openmp_wait_policy(argv);  // may execute mpmcd again, before any OpenMP call
  mpmcd::apply_allocator_policy();
  const int rc = mpmcd::app::run_cli(argc, argv);
  mpmcd::parallel::Comm::finalize();  // MPI, if a run started it
  return rc;
}
