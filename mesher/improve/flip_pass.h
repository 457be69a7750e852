// kdmesh — the flip stage of the quality-improvement pass: edge, face and boundary edge
// removals, worst tet first, each tet taking its best improving flip (part of
// mesher/improve/mesh_improve.cpp's schedule).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>

#include "mesher/improve/improve_boundary.h"
#include "mesher/improve/improve_tets.h"
#include "mesher/improve/sine_cache.h"

namespace kdmesh {

struct FlipCounts {
  std::size_t edge_removals = 0, face_removals = 0, boundary_flips = 0;
  /// With several threads: choices made again on the changed mesh, choices made in an earlier
  /// batch and still valid when their tet came up, tets sent back to the queue.
  std::size_t chosen_again = 0, reused = 0, requeued = 0;
  /// The parallel phases: flips made in the parts, tets they left to the serial phase.
  std::size_t in_parts = 0, left_by_parts = 0;
};

/// How the flip stage shares out its work. The result depends on it, never on the thread count.
struct FlipSchedule {
  /// With n >= 2 * part_tets tets below the threshold the stage begins with a parallel phase:
  /// the mesh split into 2^k parts, k = min(max_levels, floor(log2(n / part_tets))) (so about
  /// part_tets or more of them each; mesher/improve/flip_parts.h), each part's tets worked
  /// apart; what the parts leave (the tets near a cut, ...) is then worked in one queue.
  std::size_t part_tets = 32768;
  unsigned max_levels = 5;
  /// Phases of parts at most (at least one runs): each next one splits, likewise, the tets the
  /// one before left, if enough for a split (the gear box: 2.33M tets below the threshold,
  /// 715k left by a first phase of 32 parts).
  unsigned max_phases = 3;
  /// Each part's dead slots for the tets it makes: its tets below the threshold / pool_per,
  /// at least min_pool (a flip the pool cannot hold is left to the serial phase).
  std::size_t pool_per = 16, min_pool = 1024;
  /// The levels for n tets below the threshold (0: no parallel phase).
  unsigned levels(std::size_t n) const {
    unsigned k = 0;
    while (k < max_levels && part_tets > 0 && n / part_tets >= (std::size_t(2) << k)) ++k;
    return k;
  }
};

/// Flips until no tet below `threshold` has an improving edge or face removal (or, given
/// `boundary`, boundary edge removal). Tets are taken worst first (ties by id, then version);
/// each takes the best of its candidates. Returns the flips made.
///
/// The parallel phase (see FlipSchedule), when it runs, works each part's queue so, the parts
/// on different threads: a part's flips read and change only tets whose four vertices are in
/// it. The serial phase then takes the tets the parts left, in one queue.
///
/// The result is that of taking each queue's tets one at a time, whatever `threads` is: in the
/// serial phase with more than one thread, the next tets of the queue choose their flips at
/// once on the mesh as it stands, and the choices are then made in queue order; a choice
/// whose tet's vertices (or a vertex whose star it read) lie in a tet that an earlier flip of
/// the batch replaced is made again on the current mesh, and the batch ends where a new tet
/// would come first in the queue.
std::size_t flip_pass(ImproveTets& m, SineCache& cache, double threshold, int max_ring,
                      FlipCounts& counts, const BoundaryContext* boundary, unsigned threads,
                      const FlipSchedule& schedule = {});

}  // namespace kdmesh
