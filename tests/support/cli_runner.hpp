#pragma once
// Runs the mpmcd binary of the build (MPMCD_BINARY, set by tests/CMakeLists.txt) and captures its
// exit code and combined stdout/stderr: shared by the tests that drive the command line.
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace mpmcd::test_support {

// Exit code (-1 if the process did not exit normally) and combined output of one mpmcd call.
struct Result {
  int code;
  std::string output;
};

// Runs `mpmcd <args>` through the shell and waits for it.
inline Result run(const std::string& args) {
  const std::string cmd = std::string(MPMCD_BINARY) + " " + args + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf{};
  while (pipe && fgets(buf.data(), buf.size(), pipe)) out += buf.data();
  const int status = pipe ? pclose(pipe) : -1;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

}  // namespace mpmcd::test_support
