// kdmesh — tet_sine of every tet slot of the quality-improvement pass, kept up to date by its
// stages (part of mesher/improve/mesh_improve.cpp's schedule).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "mesher/improve/improve_flips.h"
#include "mesher/improve/improve_tets.h"
#include "core/parallel_collect.h"
#include "core/parallel_for.h"

namespace kdmesh {

/// tet_sine of every tet slot (+inf for dead slots), kept up to date by the passes so that a
/// stage that changes little costs little: flips set the slots they kill and create, vertex
/// passes the stars of the vertices they moved.
class SineCache {
 public:
  SineCache(const ImproveTets& m, unsigned threads) : m_(m), threads_(threads) { refresh_all(); }
  const std::vector<double>& q() const { return q_; }
  void refresh_all() {
    // The room ImproveTets keeps for the flip pools' slots: grow() then stays in place (it
    // doubled and copied the paper gear box's 196 MB of values after the first pool).
    q_.reserve(ImproveTets::slot_room(m_.capacity()));
    q_.assign(m_.capacity(), std::numeric_limits<double>::infinity());
    parallel_for(q_.size(), [&](std::size_t b, std::size_t e, unsigned) {
      for (std::size_t t = b; t < e; ++t)
        if (m_.alive(std::uint32_t(t))) q_[t] = sine_of(m_, std::uint32_t(t));
    }, 65536, threads_);
  }
  /// Sets +inf for every dead slot, the live ones keeping their values: after a pass that
  /// refreshed the tets it created but not those it killed (a refresh_all costs a tet_sine of
  /// every live tet: 0.7 s of the paper gear box's split pass, for 26 splits).
  void refresh_dead() {
    q_.resize(m_.capacity(), std::numeric_limits<double>::infinity());
    parallel_for(q_.size(), [&](std::size_t b, std::size_t e, unsigned) {
      for (std::size_t t = b; t < e; ++t)
        if (!m_.alive(std::uint32_t(t))) q_[t] = std::numeric_limits<double>::infinity();
    }, 65536, threads_);
  }
  /// Holds a value for every slot (+inf for those added since), so that set() never grows it:
  /// threads may then set different slots at once.
  void grow() { q_.resize(m_.capacity(), std::numeric_limits<double>::infinity()); }
  /// The slots whose value is below `threshold`, in order (dead slots hold +inf), found on
  /// the cache's threads.
  std::vector<std::uint32_t> below(double threshold) const {
    const double* q = q_.data();
    return parallel_collect(q_.size(), [q, threshold](std::size_t t) { return q[t] < threshold; }, 65536, threads_);
  }
  /// Hands the values over, one per tet slot (the cache is empty until assign): for a pass
  /// that keeps them up to date itself, without allocating and filling an array of its own.
  std::vector<double> take() {
    q_.resize(m_.capacity(), std::numeric_limits<double>::infinity());
    return std::move(q_);
  }
  /// Takes `q` as the cache: tet_sine of every tet slot (+inf for dead slots), as refresh_all
  /// would compute it (a pass that kept such values up to date itself).
  void assign(std::vector<double> q) {
    if (q.size() != m_.capacity())
      throw UsageError("SineCache::assign: " + std::to_string(q.size()) + " values for " +
                       std::to_string(m_.capacity()) + " tet slots");
    q_ = std::move(q);
  }
  /// Slot t changed (created, killed, or a vertex moved); returns its sine.
  double refresh(std::uint32_t t) {
    if (t >= q_.size()) q_.resize(m_.capacity(), std::numeric_limits<double>::infinity());
    return q_[t] = m_.alive(t) ? sine_of(m_, t) : std::numeric_limits<double>::infinity();
  }
  /// Slot t changed and its sine is q, computed by the caller as refresh(t) would (tet_sine of
  /// its vertices in slot order; +inf for a dead slot).
  void set(std::uint32_t t, double q) {
    if (t >= q_.size()) q_.resize(m_.capacity(), std::numeric_limits<double>::infinity());
    q_[t] = q;
  }
  /// The vertices in `moved` changed position.
  void refresh_stars(const std::vector<std::uint32_t>& moved) {
    if (moved.size() > m_.capacity() / 64) return refresh_all();
    std::vector<std::uint32_t> star;
    for (std::uint32_t v : moved) {
      m_.star(v, star);
      for (std::uint32_t t : star) refresh(t);
    }
  }

 private:
  const ImproveTets& m_;
  unsigned threads_;
  std::vector<double> q_;
};

}  // namespace kdmesh
