// Issue 19, class 3 — bounded, honest reads: inputs that are not regular files (/dev/zero, a
// symbolic link to it, a FIFO without a writer, a directory) are refused at once naming the
// file (exit 3); a batch file's size and zone count are bounded by the memory limit.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/support/run_cli.h"
#include "tests/support/sanitizer.h"

namespace {

namespace fs = std::filesystem;
using kdmesh::test::CliResult;

fs::path tmpdir() { return kdmesh::test::process_tmpdir("cli_bounded_reads"); }

/// `kdmesh <args>` under a 20 s time limit and a 4 GB address-space limit, so that a read that
/// blocks or grows without bound fails the test instead of hanging or exhausting the machine.
/// (Not the address-space limit under AddressSanitizer, which reserves terabytes of it.)
CliResult kdmesh(const std::string& args) {
#if KDMESH_UNDER_ASAN
  return kdmesh::test::run_kdmesh(args, tmpdir(), "timeout -s KILL 20");
#else
  return kdmesh::test::run_kdmesh(args, tmpdir(), "ulimit -v 4000000; timeout -s KILL 20");
#endif
}

using kdmesh::test::contains;

/// A fresh directory for one test.
fs::path fresh(const std::string& name) { return kdmesh::test::fresh_dir(tmpdir(), name); }

TEST(BoundedReads, DevZeroAndLinksToItAreRefused) {
  const fs::path d = fresh("zero");
  fs::create_symlink("/dev/zero", d / "zero.stl");
  fs::create_symlink("/dev/zero", d / "zero.xyz");
  const CliResult m = kdmesh("mesh " + (d / "zero.stl").string() + " --size 1 -q");
  EXPECT_EQ(m.code, 3) << m.err;
  EXPECT_TRUE(contains(m.err, (d / "zero.stl").string() + ": cannot read: it is a character device")) << m.err;
  const CliResult p = kdmesh("delaunay " + (d / "zero.xyz").string() + " -q");
  EXPECT_EQ(p.code, 3) << p.err;
  EXPECT_TRUE(contains(p.err, "zero.xyz")) << p.err;
  const CliResult b = kdmesh("batch /dev/zero -q");
  EXPECT_EQ(b.code, 3) << b.err;
  EXPECT_TRUE(contains(b.err, "/dev/zero")) << b.err;
}

TEST(BoundedReads, FifoWithoutWriterIsRefusedAtOnce) {
  const fs::path d = fresh("fifo");
  ASSERT_EQ(::mkfifo((d / "f.stl").c_str(), 0666), 0);
  ASSERT_EQ(::mkfifo((d / "f.yaml").c_str(), 0666), 0);
  const CliResult m = kdmesh("mesh " + (d / "f.stl").string() + " --size 1 -q");
  EXPECT_EQ(m.code, 3) << m.err;
  EXPECT_TRUE(contains(m.err, "f.stl: cannot read: it is a FIFO")) << m.err;
  const CliResult b = kdmesh("batch " + (d / "f.yaml").string() + " -q");
  EXPECT_EQ(b.code, 3) << b.err;
  EXPECT_TRUE(contains(b.err, "f.yaml")) << b.err;
}

// The batch file's bytes (yaml-cpp takes ~100 bytes of memory per byte) and each job's zone
// count are bounded by --max-memory before anything is parsed or built.
TEST(BoundedReads, ConfigSizeAndZoneCountAreBoundedByTheMemoryLimit) {
  const fs::path d = fresh("config");
  {
    std::ofstream f(d / "big.yaml");
    for (int i = 0; i < 40000; ++i) f << "# padding padding padding padding padding padding padding\n";
    f << "jobs:\n  - {name: a, input: nosuch.stl, size: 1}\n";
  }
  const CliResult big = kdmesh("batch " + (d / "big.yaml").string() + " --max-memory 100M -q");
  EXPECT_EQ(big.code, 3) << big.err;
  EXPECT_TRUE(contains(big.err, "file too large")) << big.err;
  std::ofstream(d / "x.stl") << "solid x\nendsolid x\n";  // exists; never read (refused first)
  {
    // 30,000 zones through a YAML alias: 7 bytes each, well under the size bound.
    std::ofstream f(d / "zones.yaml");
    f << "jobs:\n  - name: a\n    input: x.stl\n    size: 1\n    zones:\n"
      << "      - &z {type: point, size: 1, at: [0, 0, 0]}\n";
    for (int i = 0; i < 30000; ++i) f << "      - *z\n";
  }
  const CliResult zones = kdmesh("batch " + (d / "zones.yaml").string() + " --max-memory 100M -q");
  EXPECT_EQ(zones.code, 3) << zones.err;
  EXPECT_TRUE(contains(zones.err, "zones need more than the memory limit")) << zones.err;
}

}  // namespace
