// Issue 19, class 1 — outputs never damage anything: only regular files are created or
// replaced, batch outputs stay inside --out-dir, no output is an input or another output,
// temporaries are created exclusively, a job's outputs are committed all or nothing, and every
// subcommand cleans up on signals (children never outlive the batch).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/surface_mesh.h"
#include "io/surface_io.h"
#include "tests/support/run_cli.h"

namespace {

namespace fs = std::filesystem;
using kdmesh::test::CliResult;
using kdmesh::test::slurp;

fs::path tmpdir() { return kdmesh::test::process_tmpdir("cli_outputs"); }

CliResult kdmesh(const std::string& args) { return kdmesh::test::run_kdmesh(args, tmpdir()); }

using kdmesh::test::contains;

/// A fresh directory for one test.
fs::path fresh(const std::string& name) { return kdmesh::test::fresh_dir(tmpdir(), name); }

/// The cube [0, e]^3 as 12 outward triangles, written as STL.
fs::path write_cube(const fs::path& p, double e) {
  kdmesh::SurfaceMesh m;
  for (int i = 0; i < 8; ++i) m.points.push_back(e * (i & 1), e * ((i >> 1) & 1), e * ((i >> 2) & 1));
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads)
    for (const std::uint32_t t : {q[0], q[1], q[2], q[0], q[2], q[3]}) m.tris.push_back(t);
  kdmesh::write_stl(m, p.string());
  return p;
}

void write_text(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

bool has_temp_leftovers(const fs::path& dir) {
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (contains(e.path().filename().string(), ".tmp-")) return true;
  return false;
}

// `-o` naming a device node, a FIFO, a directory or a symbolic link: exit 6 naming the path,
// before any work (no stage ran), and the node is still what it was.
TEST(OutputsNeverClobber, DeviceNodeIsRefused) {
  const fs::path d = fresh("device");
  const fs::path stl = write_cube(d / "cube.stl", 10);
  const fs::path dev = d / "mynull";
  if (::mknod(dev.c_str(), S_IFCHR | 0666, makedev(1, 3)) != 0) GTEST_SKIP() << "mknod needs root";
  const CliResult r = kdmesh("mesh " + stl.string() + " --size 10 -o " + dev.string());
  EXPECT_EQ(r.code, 6) << r.err;
  EXPECT_TRUE(contains(r.err, dev.string() + ": exists and is a character device")) << r.err;
  EXPECT_FALSE(contains(r.err, "placing nodes")) << r.err;  // refused before any work
  EXPECT_TRUE(fs::is_character_file(dev));
  // The same for kdmesh delaunay.
  write_text(d / "p.xyz", "0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n");
  const CliResult p = kdmesh("delaunay " + (d / "p.xyz").string() + " -o " + dev.string());
  EXPECT_EQ(p.code, 6) << p.err;
  EXPECT_TRUE(fs::is_character_file(dev));
}

TEST(OutputsNeverClobber, FifoDirectoryAndSymlinkAreRefused) {
  const fs::path d = fresh("fifo");
  const fs::path stl = write_cube(d / "cube.stl", 10);
  const fs::path fifo = d / "pipe.vtu", dir = d / "dir.json", link = d / "link.xyz", victim = d / "victim";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0666), 0);
  fs::create_directories(dir);
  write_text(victim, "victim");
  fs::create_symlink(victim, link);
  for (const auto& [opt, path, kind] : {std::tuple<std::string, fs::path, std::string>{"-o", fifo, "a FIFO"},
                                        {"--summary", dir, "a directory"},
                                        {"--nodes", link, "a symbolic link"}}) {
    const CliResult r = kdmesh("mesh " + stl.string() + " --size 10 -q " + opt + " " + path.string());
    EXPECT_EQ(r.code, 6) << opt << ": " << r.err;
    EXPECT_TRUE(contains(r.err, path.string() + ": exists and is " + kind)) << r.err;
  }
  EXPECT_TRUE(fs::is_fifo(fifo));
  EXPECT_TRUE(fs::is_directory(dir));
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(slurp(victim), "victim");
  EXPECT_FALSE(has_temp_leftovers(d));
}

// A batch file cannot write outside --out-dir (default: its own directory): absolute paths,
// '..' and symbolic links leading out are refused at load time with file:line and the key.
// `kdmesh batch jobs.yaml` run in the YAML's own folder refused every output that did not
// exist yet as leading "outside the output directory through a symbolic link": the weakly
// canonical form of the relative, not yet existing path stayed relative. Found meshing the
// gear box by hand; every test had passed absolute paths.
TEST(OutputsNeverClobber, RegressionBatchRunInItsOwnFolderWritesItsOutputs) {
  const fs::path d = fresh("own_folder");
  write_cube(d / "cube.stl", 10);
  write_text(d / "jobs.yaml", "jobs:\n  - name: a\n    input: cube.stl\n    size: 10\n    output: {vtu: a.vtu, summary: a.json}\n");
  const CliResult r = kdmesh::test::run_kdmesh("batch jobs.yaml -q", tmpdir(), "cd '" + d.string() + "' &&");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(d / "a.vtu"));
  EXPECT_TRUE(fs::is_regular_file(d / "a.json"));
  // And a relative path that does lead out is still refused from there.
  write_text(d / "jobs.yaml", "jobs:\n  - name: a\n    input: cube.stl\n    size: 10\n    output: {vtu: ../b.vtu}\n");
  EXPECT_EQ(kdmesh::test::run_kdmesh("batch jobs.yaml -q", tmpdir(), "cd '" + d.string() + "' &&").code, 3);
  EXPECT_FALSE(fs::exists(d.parent_path() / "b.vtu"));
}

TEST(OutputsNeverClobber, BatchOutputsStayInsideOutDir) {
  const fs::path d = fresh("escape");
  fs::create_directories(d / "cfg" / "out");
  write_cube(d / "cfg" / "cube.stl", 10);
  const fs::path outside = d / "outside.json";
  fs::create_directory_symlink(d, d / "cfg" / "out" / "up");
  const std::vector<std::pair<std::string, int>> cases = {
      {"summary: " + outside.string(), 5}, {"vtu: ../../x.vtu", 5}, {"vtu: up/x.vtu", 5}};
  for (const auto& [output, line] : cases) {
    const fs::path yaml = d / "cfg" / "jobs.yaml";
    write_text(yaml, "jobs:\n  - name: a\n    input: cube.stl\n    size: 10\n    output: {" + output + "}\n");
    const CliResult r = kdmesh("batch " + yaml.string() + " --out-dir " + (d / "cfg" / "out").string() + " -q");
    EXPECT_EQ(r.code, 3) << output << ": " << r.err;
    EXPECT_TRUE(contains(r.err, yaml.string() + ":" + std::to_string(line) + ":")) << r.err;
    EXPECT_TRUE(contains(r.err, "key 'output'")) << r.err;
    EXPECT_TRUE(contains(r.err, "--allow-outside-out-dir")) << r.err;
    // Without --out-dir, the YAML's directory is the output directory (the link is not in it).
    if (output.find("up/") == std::string::npos) {
      EXPECT_EQ(kdmesh("batch " + yaml.string() + " -q").code, 3) << output;
    }
  }
  EXPECT_FALSE(fs::exists(outside));
  EXPECT_FALSE(fs::exists(d / "x.vtu"));
  // The explicit option allows it.
  const fs::path yaml = d / "cfg" / "jobs.yaml";
  write_text(yaml, "jobs:\n  - name: a\n    input: cube.stl\n    size: 10\n    output: {summary: " +
                       outside.string() + ", vtu: a.vtu}\n");
  const CliResult ok = kdmesh("batch " + yaml.string() + " --allow-outside-out-dir -q");
  EXPECT_EQ(ok.code, 0) << ok.err;
  EXPECT_TRUE(fs::exists(outside));
  EXPECT_TRUE(fs::exists(d / "cfg" / "a.vtu"));  // default out-dir: the YAML's directory
}

// An output that is the run's input (also through a hard link or another spelling), or two
// outputs that are one file: a usage error before anything runs; the input is untouched.
TEST(OutputsNeverClobber, OutputThatIsAnInputOrAnotherOutputIsRefused) {
  const fs::path d = fresh("same");
  const fs::path stl = write_cube(d / "x.stl", 10);
  const std::string before = slurp(stl);
  fs::create_hard_link(stl, d / "hard.vtu");
  for (const std::string& args :
       {"-o " + stl.string(), "-o " + (d / "." / "x.stl").string(), "--summary " + (d / "hard.vtu").string(),
        "-o " + (d / "a.vtu").string() + " --summary " + (d / "a.vtu").string(),
        "-o " + (d / "a.vtu").string() + " --nodes " + (d / "sub" / ".." / "a.vtu").string()}) {
    fs::create_directories(d / "sub");
    const CliResult r = kdmesh("mesh " + stl.string() + " --size 10 -q " + args);
    EXPECT_EQ(r.code, 2) << args << ": " << r.err;
    EXPECT_TRUE(contains(r.err, "are the same file")) << r.err;
  }
  EXPECT_EQ(slurp(stl), before);
  EXPECT_FALSE(fs::exists(d / "a.vtu"));
  write_text(d / "p.xyz", "0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n");
  EXPECT_EQ(kdmesh("delaunay " + (d / "p.xyz").string() + " -o " + (d / "p.xyz").string()).code, 2);
}

// In a batch: job a's output is job b's input (the result would depend on --jobs), or a
// job's output names its own input: a config error at load time, file:line, nothing runs.
TEST(OutputsNeverClobber, BatchOutputThatIsAnyJobsInputIsRefused) {
  const fs::path d = fresh("batchsame");
  write_cube(d / "a.stl", 10);
  write_cube(d / "b.stl", 10);
  const std::string before = slurp(d / "b.stl");
  const fs::path yaml = d / "jobs.yaml";
  write_text(yaml, "jobs:\n  - {name: a, input: a.stl, size: 10, output: {vtu: b.stl}}\n"
                   "  - {name: b, input: b.stl, size: 10, output: {vtu: b.vtu}}\n");
  const CliResult r = kdmesh("batch " + yaml.string() + " -q -j 2");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_TRUE(contains(r.err, yaml.string() + ":3:")) << r.err;
  EXPECT_TRUE(contains(r.err, "are the same file")) << r.err;
  write_text(yaml, "jobs:\n  - {name: a, input: a.stl, size: 10, output: {summary: ./a.stl}}\n");
  EXPECT_EQ(kdmesh("batch " + yaml.string() + " -q").code, 3);
  EXPECT_EQ(slurp(d / "b.stl"), before);
  EXPECT_FALSE(fs::exists(d / "b.vtu"));
}

// The temporary file is created exclusively under an unpredictable name: symbolic links
// planted at the names a previous version used ("<out>.tmp-<pid>-<n>") are never followed.
TEST(OutputsNeverClobber, PlantedSymlinksAreNeverFollowed) {
  const fs::path d = fresh("planted");
  const fs::path out = d / "out.json", victim = d / "victim";
  write_text(victim, "victim");
  for (int n = 0; n < 64; ++n)
    fs::create_symlink(victim, out.string() + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(n));
  for (int k = 0; k < 3; ++k) {
    kdmesh::AtomicFile f(out.string());
    ASSERT_TRUE(fs::is_regular_file(fs::symlink_status(f.temp_path()))) << f.temp_path();
    std::ofstream(f.temp_path()) << "output " << k;
    f.commit();
  }
  EXPECT_EQ(slurp(victim), "victim");
  EXPECT_EQ(slurp(out), "output 2");
}

// A job's outputs are all or nothing: when one of them cannot be written (here the summary's
// path is a directory), none of the previous files is replaced.
TEST(OutputsNeverClobber, FailedOutputReplacesNoPreviousFile) {
  const fs::path d = fresh("allornothing");
  const fs::path stl = write_cube(d / "cube.stl", 10);
  write_text(d / "a.vtu", "previous");
  write_text(d / "a.xyz", "previous");
  fs::create_directories(d / "a.json");
  const CliResult r = kdmesh("mesh " + stl.string() + " --size 10 -q -o " + (d / "a.vtu").string() + " --nodes " +
                             (d / "a.xyz").string() + " --summary " + (d / "a.json").string());
  EXPECT_EQ(r.code, 6) << r.err;
  EXPECT_EQ(slurp(d / "a.vtu"), "previous");
  EXPECT_EQ(slurp(d / "a.xyz"), "previous");
  EXPECT_FALSE(has_temp_leftovers(d));
}

// The commit itself: a target that turns into a directory after the outputs were written
// fails the whole set, and the files committed before it are restored.
TEST(OutputsNeverClobber, CommitIsAllOrNothing) {
  const fs::path d = fresh("commit");
  const fs::path a = d / "a.txt", b = d / "b.txt", c = d / "c.txt";
  write_text(a, "old a");
  write_text(b, "old b");
  {
    kdmesh::AtomicFileSet files;
    std::ofstream(files.add(a.string())) << "new a";
    std::ofstream(files.add(c.string())) << "new c";
    std::ofstream(files.add(b.string())) << "new b";
    fs::remove(b);
    fs::create_directory(b);
    EXPECT_THROW(files.commit(), kdmesh::OutputError);
  }
  EXPECT_EQ(slurp(a), "old a");
  EXPECT_FALSE(fs::exists(c));
  EXPECT_TRUE(fs::is_directory(b));
  EXPECT_FALSE(has_temp_leftovers(d));
  fs::remove(b);
  write_text(b, "old b");
  {
    kdmesh::AtomicFileSet files;
    std::ofstream(files.add(a.string())) << "new a";
    std::ofstream(files.add(b.string())) << "new b";
    files.commit();
  }
  EXPECT_EQ(slurp(a), "new a");
  EXPECT_EQ(slurp(b), "new b");
  EXPECT_FALSE(has_temp_leftovers(d));
}

/// The signals a running process catches (SigCgt of /proc/<pid>/status).
unsigned long long caught_signals(pid_t pid) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(f, line);)
    if (line.rfind("SigCgt:", 0) == 0) return std::stoull(line.substr(7), nullptr, 16);
  return 0;
}

/// Starts `kdmesh <args...>` with stdout and stderr to /dev/null; returns its pid.
pid_t spawn_kdmesh(const std::vector<std::string>& args) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::vector<char*> argv{const_cast<char*>(KDMESH_EXE)};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    std::freopen("/dev/null", "w", stdout);
    std::freopen("/dev/null", "w", stderr);
    ::execv(KDMESH_EXE, argv.data());
    ::_exit(127);
  }
  return pid;
}

// kdmesh mesh and kdmesh delaunay (every subcommand) remove their temporaries on SIGINT,
// SIGTERM and SIGHUP: their handlers are installed by main, not only in batch children.
TEST(OutputsNeverClobber, EverySubcommandCatchesInterruptTerminateAndHangup) {
  const std::string block = std::string(KDMESH_SOURCE_DIR) + "/models/block/block.stl";
  const fs::path d = fresh("signals");
  const pid_t pid = spawn_kdmesh({"mesh", block, "--size", "2", "-q", "-o", (d / "b.vtu").string()});
  ASSERT_GT(pid, 0);
  unsigned long long mask = 0;
  for (int i = 0; i < 500 && !(mask & (1ull << (SIGTERM - 1))); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    mask = caught_signals(pid);
  }
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) EXPECT_TRUE(mask & (1ull << (sig - 1))) << "signal " << sig;
  ::kill(pid, SIGHUP);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGHUP);
  EXPECT_FALSE(has_temp_leftovers(d));
}

/// The children of `pid` (/proc/<pid>/task/<pid>/children).
std::vector<pid_t> children_of(pid_t pid) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/task/" + std::to_string(pid) + "/children");
  std::vector<pid_t> out;
  for (pid_t c; f >> c;) out.push_back(c);
  return out;
}

// Killing the batch parent, even with SIGKILL, never leaves a job running.
TEST(OutputsNeverClobber, KilledBatchLeavesNoChildRunning) {
  const fs::path d = fresh("orphans");
  fs::copy_file(std::string(KDMESH_SOURCE_DIR) + "/models/block/block.stl", d / "block.stl");
  write_text(d / "jobs.yaml", "jobs:\n  - {name: slow, input: block.stl, size: 2, output: {vtu: slow.vtu}}\n");
  const pid_t parent = spawn_kdmesh({"batch", (d / "jobs.yaml").string(), "-q"});
  std::vector<pid_t> kids;
  for (int i = 0; i < 250 && kids.empty(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    kids = children_of(parent);
  }
  ASSERT_FALSE(kids.empty()) << "the batch started no job";
  ::kill(parent, SIGKILL);
  int status = 0;
  ASSERT_EQ(::waitpid(parent, &status, 0), parent);
  for (pid_t k : kids) {
    bool gone = false;
    for (int i = 0; i < 250 && !gone; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      std::ifstream st("/proc/" + std::to_string(k) + "/stat");
      std::string s;
      std::getline(st, s);
      // Gone, or a zombie waiting for init to reap it.
      gone = s.empty() || contains(s, ") Z ");
    }
    EXPECT_TRUE(gone) << "job process " << k << " still running";
    if (!gone) ::kill(k, SIGKILL);
  }
  EXPECT_FALSE(has_temp_leftovers(d));
}

}  // namespace
