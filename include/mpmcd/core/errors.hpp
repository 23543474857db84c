#pragma once
/// Error types and the process exit codes they map to.
#include <cstdint>
#include <stdexcept>
#include <string>

namespace mpmcd {

/// Process exit codes of the `mpmcd` command line.
enum class ExitCode : int {
  kOk = 0,           ///< finished normally
  kRuntime = 1,      ///< unexpected internal failure
  kInput = 2,        ///< bad input: configuration, packing file, command line
  kNumerical = 3,    ///< the simulation could not go on (divergence, NaN, J <= 0)
  kInterrupted = 4,  ///< stopped by a signal after writing its state
};

/// Bad user input. The message names the file (and line), the key and what was expected.
class InputError : public std::runtime_error {
 public:
  /// `file`: path of the offending file ("" if none); `line`: 1-based line (0 if unknown);
  /// `key`: dotted key path or field name; `expectation`: what was expected / what is wrong.
  InputError(std::string file, std::int64_t line, std::string key, std::string expectation);
  /// A free-form input error (e.g. a command-line problem).
  explicit InputError(const std::string& message);

  const std::string& file() const { return file_; }  ///< offending file, may be empty
  std::int64_t line() const { return line_; }        ///< 1-based line, 0 if unknown
  const std::string& key() const { return key_; }    ///< offending key, may be empty

 private:
  std::string file_;
  std::int64_t line_ = 0;
  std::string key_;
};

/// The simulation cannot go on: non-convergence after all time-step cuts, NaN/Inf, J <= 0, ...
class NumericalError : public std::runtime_error {
 public:
  /// `reason`: what happened; `step`: step index; `time`: [s]; `grain`, `point`: -1 if not known.
  NumericalError(const std::string& reason, std::int64_t step = -1, double time = 0.0,
                 std::int64_t grain = -1, std::int64_t point = -1);

  std::int64_t step() const { return step_; }            ///< step index where it happened
  double time() const { return time_; }                  ///< simulation time [s]
  std::int64_t grain() const { return grain_; }          ///< grain involved, -1 if none
  std::int64_t point() const { return point_; }          ///< material point involved, -1 if none
  const std::string& reason() const { return reason_; }  ///< bare reason without location

 private:
  std::string reason_;
  std::int64_t step_, grain_, point_;
  double time_;
};

}  // namespace mpmcd
