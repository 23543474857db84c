#include "mpmcd/core/openmp_env.hpp"

#include <unistd.h>

#include <cstdlib>

namespace mpmcd {

namespace {
// Set in the restarted process: never restart twice.
constexpr const char* kMarker = "MPMCD_OPENMP_ENV_SET";
}  // namespace

void apply_openmp_wait_policy(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY") || std::getenv("GOMP_SPINCOUNT") || std::getenv(kMarker))
    return;
  if (setenv("GOMP_SPINCOUNT", kGompSpinCount, 1) != 0 || setenv(kMarker, "1", 1) != 0) return;
  execv("/proc/self/exe", argv);
  // Only reached when execv failed: go on with the defaults (the variables set stay unread).
}

std::string openmp_wait_policy() {
  if (const char* p = std::getenv("OMP_WAIT_POLICY")) return std::string("OMP_WAIT_POLICY=") + p;
  if (const char* s = std::getenv("GOMP_SPINCOUNT")) return std::string("GOMP_SPINCOUNT=") + s;
  return "libgomp default";
}

}  // namespace mpmcd
