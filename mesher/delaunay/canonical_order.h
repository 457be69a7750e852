// kdmesh — a Delaunay triangulation's records in an order that depends on its tets alone
// (pipeline stage helper: Triangulation + Ordering -> Triangulation, same tets).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include "core/ordering.h"
#include "core/tet_mesh.h"
#include "mesher/delaunay/delaunay.h"

namespace kdmesh {

/// Rewrites `tri`, a triangulation delaunay() built inserting `order`, into a canonical form
/// that depends only on its tets and `order`: the parallel kernel makes the same tets on any
/// thread count, but stores them in another order and with other vertex rotations, and every
/// later stage (classification, recovery, the quality pass) breaks its ties by tet id. With
/// ranks r = position in `order` (the infinite vertex last):
///  - each tet's vertices are turned by an even permutation (orientation kept) so that the
///    vertex of least rank comes first and, of the other three, the least of the three
///    rotations second;
///  - tets are sorted by the rank of their last inserted vertex, lowest first, and tets of one
///    last vertex by their other three ranks taken largest first, in decreasing order: tets made
///    around one insertion stay together, as the kernel's own order keeps them, and the
///    infinite tets come last;
///  - exact duplicate points (stats.duplicates): every tet names, of each set of equal points,
///    the one of least rank, the one a sequential run keeps; `stats` then says so too.
/// Face references are remapped accordingly. Runs on up to `threads` threads (0:
/// available_cpus()); linear time; 53 bytes of scratch per tet (a copy of the records, keys,
/// the new order).
void canonicalize_triangulation(Triangulation& tri, const Ordering& order, DelaunayStats& stats,
                                unsigned threads = 0);

}  // namespace kdmesh
