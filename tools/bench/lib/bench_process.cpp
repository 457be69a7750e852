// kdmesh bench — child processes: fork + exec, captured output, a timeout, and ru_maxrss.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/timer.h"
#include "tools/bench/lib/bench.h"

namespace kdmesh {

namespace {

/// Reads what is available on fd into s; false at end of file (or on error).
bool drain(int fd, std::string& s) {
  char buf[8192];
  for (;;) {
    const ssize_t k = ::read(fd, buf, sizeof buf);
    if (k > 0) {
      s.append(buf, std::size_t(k));
      continue;
    }
    if (k == 0) return false;
    if (errno == EINTR) continue;
    return errno == EAGAIN || errno == EWOULDBLOCK;
  }
}

}  // namespace

ChildResult run_child(const std::vector<std::string>& argv, double timeout_seconds) {
  if (argv.empty()) throw UsageError("run_child: empty command");
  int out_pipe[2], err_pipe[2];
  if (::pipe2(out_pipe, O_CLOEXEC) != 0) throw Error("pipe: " + std::string(std::strerror(errno)));
  if (::pipe2(err_pipe, O_CLOEXEC) != 0) {
    ::close(out_pipe[0]);
    ::close(out_pipe[1]);
    throw Error("pipe: " + std::string(std::strerror(errno)));
  }
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);

  Stopwatch clock;
  const pid_t pid = ::fork();
  if (pid < 0) {
    for (int fd : {out_pipe[0], out_pipe[1], err_pipe[0], err_pipe[1]}) ::close(fd);
    throw Error("fork: " + std::string(std::strerror(errno)));
  }
  if (pid == 0) {
    // Child: only async-signal-safe calls until exec. dup2 clears O_CLOEXEC on 1 and 2.
    ::dup2(out_pipe[1], STDOUT_FILENO);
    ::dup2(err_pipe[1], STDERR_FILENO);
    ::execv(args[0], args.data());
    static const char msg[] = "exec failed\n";
    [[maybe_unused]] const ssize_t w = ::write(STDERR_FILENO, msg, sizeof msg - 1);
    ::_exit(127);
  }
  ::close(out_pipe[1]);
  ::close(err_pipe[1]);
  ::fcntl(out_pipe[0], F_SETFL, O_NONBLOCK);
  ::fcntl(err_pipe[0], F_SETFL, O_NONBLOCK);

  ChildResult r;
  bool out_open = true, err_open = true;
  while (out_open || err_open) {
    int wait_ms = 200;
    if (timeout_seconds > 0) {
      const double left = timeout_seconds - clock.seconds();
      if (left <= 0) {
        r.timed_out = true;
        ::kill(pid, SIGKILL);
        break;
      }
      wait_ms = int(std::min(200.0, left * 1000.0)) + 1;
    }
    pollfd fds[2];
    nfds_t k = 0;
    if (out_open) fds[k++] = {out_pipe[0], POLLIN, 0};
    if (err_open) fds[k++] = {err_pipe[0], POLLIN, 0};
    if (::poll(fds, k, wait_ms) < 0 && errno != EINTR) break;
    if (out_open) out_open = drain(out_pipe[0], r.out);
    if (err_open) err_open = drain(err_pipe[0], r.err);
  }
  ::close(out_pipe[0]);
  ::close(err_pipe[0]);

  int status = 0;
  rusage ru{};
  while (::wait4(pid, &status, 0, &ru) < 0) {
    if (errno != EINTR) throw Error("wait4: " + std::string(std::strerror(errno)));
  }
  r.wall_seconds = clock.seconds();
  r.peak_rss_bytes = double(ru.ru_maxrss) * 1024.0;  // Linux reports kilobytes
  if (WIFEXITED(status)) {
    r.exit_code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    r.signal = WTERMSIG(status);
  }
  return r;
}

std::string find_program(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    std::size_t end = dirs.find(':', start);
    if (end == std::string::npos) end = dirs.size();
    const std::string dir = dirs.substr(start, end - start);
    if (!dir.empty()) {
      const std::string candidate = dir + "/" + name;
      struct stat st {};
      if (::stat(candidate.c_str(), &st) == 0 && S_ISREG(st.st_mode) &&
          ::access(candidate.c_str(), X_OK) == 0)
        return candidate;
    }
    start = end + 1;
  }
  return {};
}

}  // namespace kdmesh
