// kdmesh — values of a function at points, kept by the points' exact coordinates (the
// resource estimate's facet corners, which its triangle splits share).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace kdmesh {

/// f(p) for points p, each computed once until clear(): points equal coordinate by coordinate
/// (==) share one value. Open addressing, at most 5/8 full; clear() costs the points put since
/// the last one. Not thread-safe: one per thread.
///
/// The resource estimate's surface integral asks for h at the three corners of every triangle
/// it takes, and a split's three midpoints are corners of its four children and of their
/// neighbours: on occt_sh2.stl at diag/20 the integral was 0.4 CPU-s of the estimate's 1.2,
/// most of it corners asked again.
class PointValues {
 public:
  /// f(p), computed (and `computed` counted up) the first time p is asked for.
  template <class F>
  double at(const double* p, F&& f, std::uint64_t& computed) {
    if (8 * (used_.size() + 1) > 5 * slots_.size()) grow();
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = hash(p) & mask;; i = (i + 1) & mask) {
      Slot& s = slots_[i];
      if (!s.used) {
        s = Slot{{p[0], p[1], p[2]}, f(p), true};
        used_.push_back(i);
        ++computed;
        return s.value;
      }
      if (s.p[0] == p[0] && s.p[1] == p[1] && s.p[2] == p[2]) return s.value;
    }
  }
  /// Forgets every point.
  void clear() {
    for (const std::size_t i : used_) slots_[i].used = false;
    used_.clear();
  }
  std::size_t size() const { return used_.size(); }

 private:
  struct Slot {
    double p[3];
    double value;
    bool used;
  };
  static std::size_t hash(const double* p) {
    double q[3] = {p[0], p[1], p[2]};
    for (double& x : q)
      if (x == 0) x = 0;  // -0.0 == 0.0: one hash for both
    std::uint64_t b[3];
    std::memcpy(b, q, sizeof b);
    std::uint64_t x = b[0] * 0x9E3779B97F4A7C15ULL ^ b[1] * 0xC2B2AE3D27D4EB4FULL ^ b[2] * 0x165667B19E3779F9ULL;
    x ^= x >> 29;
    return std::size_t((x * 0xBF58476D1CE4E5B9ULL) >> 17);
  }
  void grow() {
    std::vector<Slot> old(std::max<std::size_t>(64, 2 * slots_.size()), Slot{{0, 0, 0}, 0, false});
    old.swap(slots_);
    used_.clear();
    const std::size_t mask = slots_.size() - 1;
    for (const Slot& s : old) {
      if (!s.used) continue;
      std::size_t i = hash(s.p) & mask;
      while (slots_[i].used) i = (i + 1) & mask;
      slots_[i] = s;
      used_.push_back(i);
    }
  }
  std::vector<Slot> slots_;
  std::vector<std::size_t> used_;
};

}  // namespace kdmesh
