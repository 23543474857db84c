#include "mpmcd/core/errors.hpp"

#include <fmt/format.h>

namespace mpmcd {

namespace {
std::string input_message(const std::string& file, std::int64_t line, const std::string& key,
                          const std::string& expectation) {
  std::string where = file.empty() ? std::string("input") : file;
  if (line > 0) where += fmt::format(":{}", line);
  if (key.empty()) return fmt::format("{}: {}", where, expectation);
  return fmt::format("{}: key '{}': {}", where, key, expectation);
}
std::string numerical_message(const std::string& reason, std::int64_t step, double time,
                              std::int64_t grain, std::int64_t point) {
  std::string msg = reason;
  if (step >= 0) msg += fmt::format(" (step {}, t = {:.9g} s", step, time);
  if (step >= 0 && grain >= 0) msg += fmt::format(", grain {}", grain);
  if (step >= 0 && point >= 0) msg += fmt::format(", point {}", point);
  if (step >= 0) msg += ")";
  return msg;
}
}  // namespace

InputError::InputError(std::string file, std::int64_t line, std::string key,
                       std::string expectation)
    : std::runtime_error(input_message(file, line, key, expectation)),
      file_(std::move(file)),
      line_(line),
      key_(std::move(key)) {}

InputError::InputError(const std::string& message) : std::runtime_error(message) {}

NumericalError::NumericalError(const std::string& reason, std::int64_t step, double time,
                               std::int64_t grain, std::int64_t point)
    : std::runtime_error(numerical_message(reason, step, time, grain, point)),
      reason_(reason),
      step_(step),
      grain_(grain),
      point_(point),
      time_(time) {}

}  // namespace mpmcd
