// kdmesh — a few threads kept for many short parallel steps (where starting threads per step,
// as parallel_for does, would cost more than the step).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <atomic>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

namespace kdmesh {

/// run(job) calls job(w) for w = 0 .. size() - 1, job(0) on the calling thread and the others
/// on threads started once by the constructor, and returns when all have returned (the first
/// exception thrown is rethrown). The helpers wait in std::atomic::wait between steps. One
/// caller at a time.
class WorkerTeam {
 public:
  /// Up to `workers` in all (at least one: the caller); fewer if threads cannot be started.
  explicit WorkerTeam(unsigned workers) {
    for (unsigned w = 1; w < workers; ++w) {
      try {
        helpers_.emplace_back([this, w] { serve(w); });
      } catch (const std::system_error&) {
        break;
      }
    }
  }
  ~WorkerTeam() {
    stop_.store(true, std::memory_order_relaxed);
    generation_.fetch_add(1, std::memory_order_release);
    generation_.notify_all();
    for (std::thread& t : helpers_) t.join();
  }
  WorkerTeam(const WorkerTeam&) = delete;
  WorkerTeam& operator=(const WorkerTeam&) = delete;

  unsigned size() const { return unsigned(helpers_.size()) + 1; }

  void run(const std::function<void(unsigned)>& job) {
    if (helpers_.empty()) return job(0);
    job_ = &job;
    pending_.store(std::uint32_t(helpers_.size()), std::memory_order_relaxed);
    generation_.fetch_add(1, std::memory_order_release);
    generation_.notify_all();
    try {
      job(0);
    } catch (...) {
      keep(std::current_exception());
    }
    for (std::uint32_t p; (p = pending_.load(std::memory_order_acquire)) != 0;)
      pending_.wait(p, std::memory_order_acquire);
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  }

 private:
  void serve(unsigned w) {
    std::uint32_t seen = 0;
    for (;;) {
      generation_.wait(seen, std::memory_order_acquire);
      seen = generation_.load(std::memory_order_acquire);
      if (stop_.load(std::memory_order_relaxed)) return;
      try {
        (*job_)(w);
      } catch (...) {
        keep(std::current_exception());
      }
      if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) pending_.notify_one();
    }
  }
  void keep(std::exception_ptr e) {
    const std::lock_guard<std::mutex> lock(error_mutex_);
    if (!error_) error_ = std::move(e);
  }

  std::vector<std::thread> helpers_;
  std::atomic<std::uint32_t> generation_{0}, pending_{0};
  std::atomic<bool> stop_{false};
  const std::function<void(unsigned)>* job_ = nullptr;
  std::mutex error_mutex_;
  std::exception_ptr error_;
};

}  // namespace kdmesh
