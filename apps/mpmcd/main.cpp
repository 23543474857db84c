// mpmcd command line: all logic lives in the app module (src/app/cli.cpp).
#include "mpmcd/app/cli.hpp"
#include "mpmcd/parallel/comm.hpp"

int main(int argc, char** argv) {
  const int rc = mpmcd::app::run_cli(argc, argv);
  mpmcd::parallel::Comm::finalize();  // MPI, if a run started it
  return rc;
}
