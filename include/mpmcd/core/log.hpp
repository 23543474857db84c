#pragma once
/// Logging through spdlog: one named logger "mpmcd" shared by all modules.
#include <spdlog/spdlog.h>

namespace mpmcd {

/// Verbosity of the console log.
enum class Verbosity { kQuiet, kNormal, kVerbose };

/// Configures the "mpmcd" logger (console, stderr) at the given verbosity. Idempotent.
void setup_logging(Verbosity verbosity);

/// The "mpmcd" logger (created on first use with normal verbosity).
spdlog::logger& log();

}  // namespace mpmcd
