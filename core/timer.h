// kdmesh — wall-clock stopwatch for per-stage timings.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <chrono>

namespace kdmesh {

class Stopwatch {
 public:
  Stopwatch() : t0_(clock::now()) {}
  void reset() { t0_ = clock::now(); }
  double seconds() const { return std::chrono::duration<double>(clock::now() - t0_).count(); }

 private:
  using clock = std::chrono::steady_clock;
  clock::time_point t0_;
};

}  // namespace kdmesh
