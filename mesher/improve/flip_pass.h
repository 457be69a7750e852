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
};

/// Flips until no tet below `threshold` has an improving edge or face removal (or, given
/// `boundary`, boundary edge removal). Tets are taken worst first (ties by id, then version);
/// each takes the best of its candidates. Returns the flips made.
///
/// The result is that of taking the tets one at a time, whatever `threads` is: with more than
/// one thread, the next tets of the queue choose their flips at once on the mesh as it stands,
/// and the choices are then made in queue order; a choice whose tet's vertices (or a vertex
/// whose star it read) lie in a tet that an earlier flip of the batch replaced is made again
/// on the current mesh, and the batch ends where a new tet would come first in the queue.
std::size_t flip_pass(ImproveTets& m, SineCache& cache, double threshold, int max_ring,
                      FlipCounts& counts, const BoundaryContext* boundary, unsigned threads);

}  // namespace kdmesh
