// Test support: scratch file paths under the build's test directory.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <functional>
#include <string>

namespace kdmesh::test {

/// A fresh path under KDMESH_TEST_TMP/<area>, unique per test and call: "<suite>.<test>-<n><ext>".
/// Reruns overwrite, so the directory does not grow; files stay for inspection after a failure.
inline std::string scratch_path(const std::string& area, const std::string& ext) {
  namespace fs = std::filesystem;
  static std::string current_test;
  static int counter = 0;
  const fs::path dir = fs::path(KDMESH_TEST_TMP) / area;
  fs::create_directories(dir);
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string test = std::string(info->test_suite_name()) + "." + info->name();
  if (test != current_test) {
    current_test = test;
    counter = 0;
  }
  const fs::path p = dir / (test + "-" + std::to_string(counter++) + ext);
  fs::remove_all(p);
  return p.string();
}

/// Temporary files of this process (".tmp-<pid>-", core/atomic_file.h) left in `dir`. Only
/// this process's: ctest runs the tests of one binary as parallel processes that share the
/// scratch directory, and another test's writer may hold a temporary there at that moment
/// (XdmfFormat.ReplacesRegularFilesAtomically failed so under ctest -j2).
inline int temporaries_in(const std::filesystem::path& dir) {
  const std::string mine = ".tmp-" + std::to_string(::getpid()) + "-";
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().filename().string().find(mine) != std::string::npos) ++n;
  return n;
}

/// A writer refuses paths it cannot write: `write(path)` throws E naming the path when its
/// directory is missing, and (unless root, who ignores permissions) throws E into a read-only
/// directory leaving no temporary behind. `dir` must exist; `name` is the file name to try.
template <class E>
void expect_unwritable_refused(const std::filesystem::path& dir, const std::string& name,
                               const std::function<void(const std::string&)>& write) {
  const std::string missing = (dir / "no" / "such" / name).string();
  try {
    write(missing);
    ADD_FAILURE() << "no error for " << missing;
  } catch (const E& e) {
    EXPECT_EQ(e.file(), missing);
  }
  if (::geteuid() != 0) {
    const std::filesystem::path ro = dir / "ro";
    std::filesystem::create_directories(ro);
    std::filesystem::permissions(ro, std::filesystem::perms::owner_read | std::filesystem::perms::owner_exec);
    EXPECT_THROW(write((ro / name).string()), E);
    EXPECT_EQ(temporaries_in(ro), 0);
    std::filesystem::permissions(ro, std::filesystem::perms::owner_all);
  }
}

}  // namespace kdmesh::test
