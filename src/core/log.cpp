#include "mpmcd/core/log.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>

namespace mpmcd {

namespace {
std::shared_ptr<spdlog::logger> make_logger() {
  auto existing = spdlog::get("mpmcd");
  if (existing) return existing;
  auto logger = spdlog::stderr_color_mt("mpmcd");
  logger->set_pattern("[%L] %v");
  logger->set_level(spdlog::level::info);
  return logger;
}
}  // namespace

spdlog::logger& log() {
  static std::shared_ptr<spdlog::logger> logger = make_logger();
  return *logger;
}

void setup_logging(Verbosity verbosity) {
  auto& l = log();
  switch (verbosity) {
    case Verbosity::kQuiet:
      l.set_level(spdlog::level::warn);
      break;
    case Verbosity::kNormal:
      l.set_level(spdlog::level::info);
      break;
    case Verbosity::kVerbose:
      l.set_level(spdlog::level::debug);
      break;
  }
}

}  // namespace mpmcd
