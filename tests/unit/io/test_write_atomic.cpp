// io::write_file_atomic when the disk refuses the data (issue 17): the message names the reason
// and the partial .tmp file is removed; the previous file is left as it was.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "../../support/scratch.hpp"
#include "mpmcd/io/vtu.hpp"

namespace fs = std::filesystem;

TEST(WriteFileAtomic, AFailedWriteNamesTheReasonAndLeavesNoTmp) {
  const fs::path dir = mpmcd::test_support::scratch_dir("test", "write");
  const std::string path = (dir / "snapshot.vtu").string();
  mpmcd::io::write_file_atomic(path, "old\n");
  // A file-size limit stands in for a full disk: write(2) fails (EFBIG instead of ENOSPC; the
  // signal it also raises is ignored, as a full disk raises none).
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit old_limit{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  rlimit small = old_limit;
  small.rlim_cur = 4096;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  std::string message;
  try {
    mpmcd::io::write_file_atomic(path, std::string(100000, 'x'));
  } catch (const std::runtime_error& e) {
    message = e.what();
  }
  setrlimit(RLIMIT_FSIZE, &old_limit);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_EQ(message, "cannot write '" + path + ".tmp': " + std::strerror(EFBIG));
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_EQ(ss.str(), "old\n");
  // A folder that does not exist: the reason too.
  try {
    mpmcd::io::write_file_atomic((dir / "no" / "x.vtu").string(), "x");
    ADD_FAILURE() << "wrote into a missing folder";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(std::strerror(ENOENT)), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}
