// kdmesh — running meshing jobs in child processes.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "tools/app/job_process.h"

#include <poll.h>
#include <sys/prctl.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/timer.h"

namespace kdmesh {

namespace {

// Running children, for the forwarding signal handler (no allocation or locks in a handler).
constexpr int kMaxChildren = 1024;
std::atomic<pid_t> g_children[kMaxChildren];

extern "C" void forward_to_children_and_die(int sig) {
  for (std::atomic<pid_t>& c : g_children) {
    const pid_t pid = c.load();
    if (pid > 0) ::kill(pid, sig);
  }
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

void write_all(int fd, const std::string& s) {
  for (std::size_t done = 0; done < s.size();) {
    const ssize_t n = ::write(fd, s.data() + done, s.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;  // the parent is gone; nothing useful left to do
    done += std::size_t(n);
  }
}

/// The child: run the job, send "<exit code>\n<summary json>" and exit with the job's code.
[[noreturn]] void child_main(const MeshJob& job, const MeshJobCallbacks& cb, int fd, pid_t parent) {
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  std::signal(SIGHUP, SIG_DFL);
  remove_temporaries_on_signal();
  // If the parent dies (even of SIGKILL), SIGTERM: remove the temporaries and stop.
  ::prctl(PR_SET_PDEATHSIG, SIGTERM);
  if (::getppid() != parent) std::raise(SIGTERM);  // it died before prctl took effect
  MeshJobCallbacks callbacks = cb;
  if (const char* c = std::getenv("KDMESH_INJECT_CRASH")) {  // "<job>" or "<job>@<log prefix>"
    const std::string spec = c;
    const std::size_t at = spec.find('@');
    if (spec.substr(0, at) == job.name) {
      if (at == std::string::npos) std::raise(SIGSEGV);
      callbacks.log = [cb, prefix = spec.substr(at + 1)](const std::string& s) {
        if (s.compare(0, prefix.size(), prefix) == 0) std::raise(SIGSEGV);
        if (cb.log) cb.log(s);
      };
    }
  }
  MeshJobResult r;
  try {
    r = run_mesh_job(job, callbacks);
  } catch (...) {  // never by contract
    r.code = ExitCode::failure;
    r.summary = {{"job", job.name}, {"status", "failed"},
                 {"error", {{"type", "internal"}, {"exit_code", 1},
                            {"message", "unexpected error escaped the job"}}}};
  }
  write_all(fd, std::to_string(int(r.code)) + "\n" + r.summary.dump());
  ::close(fd);
  std::cout.flush();
  std::cerr.flush();
  std::_Exit(int(r.code));  // no atexit handlers or static destructors of the parent's state
}

/// The result of a child that produced no complete summary.
MeshJobResult lost_child(const MeshJob& job, int status, double seconds) {
  std::string why;
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    why = "crashed: killed by signal " + std::to_string(sig) + " (" + strsignal(sig) + ")";
    if (sig == SIGKILL) why += "; out of memory (the kernel's OOM killer)?";
  } else {
    why = "exited with status " + std::to_string(WEXITSTATUS(status)) + " without a result";
  }
  MeshJobResult r;
  r.code = ExitCode::failure;
  r.summary = {{"job", job.name}, {"input", job.input}, {"status", "failed"},
               {"seconds", {{"total", seconds}}},
               {"error", {{"type", error_type_name(ExitCode::failure)}, {"exit_code", 1},
                          {"message", "job '" + job.name + "' " + why +
                                          "; no output was written, the other jobs are unaffected"}}}};
  return r;
}

/// Parses a child's "<code>\n<json>"; false if incomplete.
bool parse_result(const std::string& text, MeshJobResult& r) {
  const std::size_t nl = text.find('\n');
  if (nl == std::string::npos || nl == 0) return false;
  try {
    const int code = std::stoi(text.substr(0, nl));
    r.summary = nlohmann::json::parse(text.begin() + long(nl) + 1, text.end());
    r.code = ExitCode(code);
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

/// The result of a child stopped because it ran over its time limit.
MeshJobResult timed_out_child(const MeshJob& job, double seconds) {
  MeshJobResult r;
  r.code = ExitCode::resource;
  r.summary = {{"job", job.name}, {"input", job.input}, {"status", "failed"},
               {"seconds", {{"total", seconds}}},
               {"error", {{"type", error_type_name(ExitCode::resource)}, {"exit_code", int(ExitCode::resource)},
                          {"message", "job '" + job.name + "' ran over its time limit of " + std::to_string(job.timeout) +
                                          " s (timeout / --timeout) and was stopped; no output was written"}}}};
  return r;
}

struct Running {
  std::size_t job;
  pid_t pid;
  int fd;
  std::string text;
  int slot;
  Stopwatch clock;
  int stop_signals = 0;  ///< signals sent for the time limit: SIGTERM, then SIGKILL
};

/// Grace after SIGTERM before SIGKILL, for a job over its time limit (seconds).
constexpr double kKillGrace = 5;

}  // namespace

std::vector<MeshJobResult> run_jobs_in_processes(
    const std::vector<MeshJob>& jobs, unsigned workers,
    const std::function<MeshJobCallbacks(std::size_t)>& callbacks,
    const std::function<void(std::size_t, const MeshJobResult&)>& done) {
  std::vector<MeshJobResult> results(jobs.size());
  if (workers == 0) workers = 1;
  if (workers > unsigned(kMaxChildren)) workers = kMaxChildren;
  auto old_int = std::signal(SIGINT, forward_to_children_and_die);
  auto old_term = std::signal(SIGTERM, forward_to_children_and_die);
  auto old_hup = std::signal(SIGHUP, forward_to_children_and_die);
  const pid_t self = ::getpid();
  std::cout.flush();
  std::cerr.flush();

  std::vector<Running> running;
  std::size_t next = 0;
  while (next < jobs.size() || !running.empty()) {
    while (next < jobs.size() && running.size() < workers) {
      int fds[2];
      if (::pipe(fds) != 0) throw Error(std::string("cannot create a pipe: ") + std::strerror(errno));
      const std::size_t i = next++;
      const MeshJobCallbacks cb = callbacks ? callbacks(i) : MeshJobCallbacks{};
      const pid_t pid = ::fork();
      if (pid < 0) {
        const int err = errno;
        ::close(fds[0]);
        ::close(fds[1]);
        if (err == EAGAIN && !running.empty()) {
          // A limit on processes (a batch system's, ulimit -u): the jobs left wait for those
          // running, at most as many at once as run now.
          --next;
          workers = unsigned(running.size());
          std::cerr << ("kdmesh: cannot start another job process (" + std::string(std::strerror(err)) +
                        "): running " + std::to_string(workers) + " job(s) at a time\n")
                    << std::flush;
          break;
        }
        throw Error(std::string("cannot start a job process: ") + std::strerror(err));
      }
      if (pid == 0) {
        ::close(fds[0]);
        for (const Running& r : running) ::close(r.fd);
        child_main(jobs[i], cb, fds[1], self);
      }
      ::close(fds[1]);
      int slot = 0;
      while (g_children[slot].load() > 0) ++slot;  // a free slot exists: running < kMaxChildren
      g_children[slot].store(pid);
      running.push_back({i, pid, fds[0], {}, slot, Stopwatch()});
    }
    // Time limits: SIGTERM at the limit (the child removes its temporaries), SIGKILL after a
    // grace; the poll wakes up for the next deadline.
    double wait = -1;
    for (Running& r : running) {
      const double limit = jobs[r.job].timeout;
      if (!(limit > 0)) continue;
      double left = limit + kKillGrace * r.stop_signals - r.clock.seconds();
      while (left <= 0 && r.stop_signals < 2) {
        ::kill(r.pid, r.stop_signals == 0 ? SIGTERM : SIGKILL);
        ++r.stop_signals;
        left = limit + kKillGrace * r.stop_signals - r.clock.seconds();
      }
      if (r.stop_signals < 2) wait = wait < 0 ? left : std::min(wait, left);
    }
    std::vector<pollfd> polls;
    for (const Running& r : running) polls.push_back({r.fd, POLLIN, 0});
    const int wait_ms = wait < 0 ? -1 : int(std::min(wait * 1000 + 1, 1e9));
    if (::poll(polls.data(), polls.size(), wait_ms) < 0) {
      if (errno == EINTR) continue;
      throw Error(std::string("poll failed: ") + std::strerror(errno));
    }
    for (std::size_t k = running.size(); k-- > 0;) {
      if (!(polls[k].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      Running& r = running[k];
      char buf[65536];
      const ssize_t n = ::read(r.fd, buf, sizeof buf);
      if (n < 0 && errno == EINTR) continue;
      if (n > 0) {
        r.text.append(buf, std::size_t(n));
        continue;
      }
      // End of file: the child has finished (or died).
      ::close(r.fd);
      int status = 0;
      while (::waitpid(r.pid, &status, 0) < 0 && errno == EINTR) {
      }
      g_children[r.slot].store(0);
      const MeshJob& job = jobs[r.job];
      MeshJobResult& result = results[r.job];
      const bool clean_exit = WIFEXITED(status);
      if (r.stop_signals > 0 && !(clean_exit && parse_result(r.text, result) && result.ok())) {
        result = timed_out_child(job, r.clock.seconds());
        for (const std::string& path : output_paths(job)) remove_temporaries_of(path, long(r.pid));
      } else if (!clean_exit || !parse_result(r.text, result)) {
        result = lost_child(job, status, r.clock.seconds());
        for (const std::string& path : output_paths(job)) remove_temporaries_of(path, long(r.pid));
      }
      if (done) done(r.job, result);
      running.erase(running.begin() + long(k));
    }
  }
  std::signal(SIGINT, old_int);
  std::signal(SIGTERM, old_term);
  std::signal(SIGHUP, old_hup);
  return results;
}

}  // namespace kdmesh
