// Atomic outputs: commit renames into place, abandonment and signals leave nothing behind.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/atomic_file.h"
#include "core/error.h"
#include "tests/support/scratch.h"

namespace kdmesh {
namespace {

namespace fs = std::filesystem;

void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

TEST(AtomicFile, CommitRenamesIntoPlace) {
  const std::string path = test::scratch_path("atomic", ".txt");
  std::string temp;
  {
    AtomicFile out(path);
    temp = out.temp_path();
    write_text(temp, "done");
    EXPECT_FALSE(fs::exists(path));  // nothing under the final name before commit
    out.commit();
  }
  EXPECT_TRUE(fs::exists(path));
  EXPECT_FALSE(fs::exists(temp));
}

TEST(AtomicFile, AbandonedOutputLeavesNothing) {
  const std::string path = test::scratch_path("atomic", ".txt");
  std::string temp;
  try {
    AtomicFile out(path);
    temp = out.temp_path();
    write_text(temp, "half");
    throw Error("stage failed");
  } catch (const Error&) {
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::exists(temp));
}

// A process killed by SIGINT or SIGTERM while writing removes its temporary files and still
// dies of the signal (so shells and batch runners see the interruption).
TEST(AtomicFile, SignalRemovesTemporariesAndKeepsSignalStatus) {
  for (int sig : {SIGINT, SIGTERM}) {
    const std::string path = test::scratch_path("atomic", ".txt");
    const std::string temp_file = path + ".temp-name";
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      remove_temporaries_on_signal();
      AtomicFile out(path);
      write_text(out.temp_path(), "half-written");
      write_text(temp_file, out.temp_path());  // tell the parent the name
      std::raise(sig);
      _exit(0);  // not reached
    }
    int status = 0;
    ASSERT_EQ(waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFSIGNALED(status)) << "signal " << sig;
    EXPECT_EQ(WTERMSIG(status), sig);
    std::ifstream in(temp_file);
    std::string temp;
    std::getline(in, temp);
    ASSERT_FALSE(temp.empty());
    EXPECT_FALSE(fs::exists(temp)) << temp;
    EXPECT_FALSE(fs::exists(path));
  }
}

}  // namespace
}  // namespace kdmesh
