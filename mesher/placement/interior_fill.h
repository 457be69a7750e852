// kdmesh — nodes inside the solid: an adaptive body-centred cubic lattice (part of node placement).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <functional>
#include <memory>

#include "mesher/node_set.h"
#include "mesher/placement/spacing_grid.h"
#include "mesher/surface/surface_query.h"
#include "sizing/sizing_field.h"

namespace kdmesh {

struct InteriorFillOptions {
  /// Lattice cube edge a = kappa * h. A BCC lattice's Delaunay tets all have 4 edges of
  /// a sqrt(3)/2 and 2 of a; per point 4 short and 3 long edges, mean 0.9234 a, so
  /// kappa = 1.083 gives mean edge / h = 1 where h is uniform.
  double kappa = 1.083;
  /// Lattice levels: a_k = kappa * h_max * rho^-k, k = 0, 1, ...; a point of level k is kept
  /// where round(log_rho(h_max / h(p))) = k, so a / (kappa h) stays in [rho^-1/2, rho^1/2].
  /// Measured (bench_placement, graded box): rho = 2^(1/3) gives fewer edges in
  /// [0.7, 1.4] h than sqrt(2) (more level transitions, each leaving gaps); 2 gives short edges.
  double rho = 1.4142135623730951;  // sqrt(2)
  /// Spacing against nodes already in the grid: |p - q| >= beta * (h_p + h_q) / 2. Must stay
  /// below sqrt(3)/2 * kappa / sqrt(rho) = 0.789 so that one level's own points never clash.
  double beta = 0.75;
  /// Nodes keep distance(p, surface) >= clearance * h(p).
  double clearance = 0.8;
  /// Boundary layer: after the lattice, each surface node proposes `layer_tries` random points
  /// at depth [clearance, clearance + layer_depth] * h below its facet, up to 0.6 h sideways;
  /// kept under the same rules, they fill gaps between the surface and the first lattice
  /// layer, whose depth varies by up to half a lattice cell. 0 = off. Random sequential
  /// addition leaves holes until it saturates: with 6 tries the layer under handle.ply's flat
  /// faces had interior nodes 2-8 h apart, and the tets between them and the surface nodes were
  /// slivers (114 tets under 5 deg at diag/40, 4 with 32 tries, for 5% more nodes and time).
  int layer_tries = 32;
  double layer_depth = 0.3;
  /// Turn the lattice by a fixed rotation (kLatticeAxes in interior_fill.cpp, exact in
  /// integers) so that none of its rows and planes of low index (the 13 directions <100>,
  /// <110>, <111>) lies within 4.7 deg of a coordinate plane. Parts are often modelled along
  /// the axes; a lattice row parallel to a row of surface nodes on an axis-aligned crease made
  /// sheets of coplanar nodes, hence slivers the quality pass could not undo (handle.ply, a
  /// cylinder faceted in strips along y: min dihedral 10.3 / 7.7 deg at diag/40 / 80 with the
  /// axis-aligned lattice; the same part turned by three random rotations gave 12.5-15.1 /
  /// 12.4-20.2).
  /// false: the lattice's axes are the coordinate axes. Either way the lattice is anchored at
  /// the origin of coordinates.
  bool rotate_lattice = true;
  std::uint64_t seed = 1;  ///< for the boundary layer
  /// Surface nodes on facets with this id or above propose boundary-layer points on both sides
  /// of their facet (the interfaces between touching bodies, mesher/placement/node_placement.cpp).
  std::uint32_t two_sided_from = kNoFacet;
  /// Threads for candidate generation (the result does not depend on it).
  unsigned threads = 2;
  /// Skip the sizing field's evaluation at a lattice point whose level the block's bounds
  /// decide to be another (h is Lipschitz; the same nodes either way). false evaluates every
  /// point: a self-check for tests.
  bool bound_levels = true;
};

struct InteriorFillStats {
  std::size_t candidates = 0;       ///< lattice points of the right level, inside and clear
  std::size_t distance_queries = 0; ///< AABB distance queries made
  std::size_t side_queries = 0;     ///< ray-cast inside tests made
  std::size_t blocks = 0;           ///< octree leaves visited
  std::size_t lattice_nodes = 0;    ///< accepted lattice nodes
  std::size_t layer_nodes = 0;      ///< accepted boundary-layer nodes
};

/// Fills the solid bounded by `query`'s surface (bbox lo..hi) with lattice nodes, strictly
/// inside (query.side(p) == +1) and at least clearance * h(p) from the surface. Octree blocks
/// are classified once (one distance query at their centre): blocks far from the surface
/// skip every per-node test, blocks outside are dropped, and only nodes near the surface get
/// their own distance query (their side follows from a surface-free ball overlapping the
/// block centre's, else a ray cast). Candidates are accepted finest level first, then in
/// block order, against the nodes already in `grid`. Appends to `nodes` (kind interior,
/// facet kNoFacet) and `grid`. Deterministic. The boundary layer reads the surface nodes
/// (kind != interior) already in `nodes` and the facets of `surface`.
InteriorFillStats fill_interior(const SurfaceMesh& surface, const double* lo, const double* hi,
                                const SurfaceQuery& query,
                                const SizingField& sizing, const InteriorFillOptions& options,
                                SpacingGrid& grid, NodeSet& nodes,
                                const std::function<void(double)>& progress = {});

/// fill_interior in its two parts, for a caller that overlaps the first with other work. The
/// lattice's candidates (each octree block's points of the right level, inside and clear of
/// the surface) depend on `query`'s surface and the sizing field only, not on the nodes placed
/// before: node placement generates them on a helper thread while it samples the surface on
/// its own. fill_interior(...) is InteriorLattice(...), work_on(options.threads) and
/// finish(...); the nodes are the same however many threads called work().
class InteriorLattice {
 public:
  /// Throws UsageError for invalid options (as fill_interior). `query` and `sizing` must
  /// outlive the lattice.
  InteriorLattice(const double* lo, const double* hi, const SurfaceQuery& query,
                  const SizingField& sizing, const InteriorFillOptions& options);
  ~InteriorLattice();
  InteriorLattice(const InteriorLattice&) = delete;
  InteriorLattice& operator=(const InteriorLattice&) = delete;
  /// Generates the candidates of the octree's root blocks not yet taken, until none is left.
  /// Any number of threads may call it at once; an error is kept for finish().
  void work();
  /// work() on `threads` threads (the calling one among them); returns when all is done.
  void work_on(unsigned threads);
  /// Makes every work() return after its current block (for a caller that gives up).
  void stop();
  /// Once every work() has returned: accepts the candidates finest level first against the
  /// nodes in `grid`, then adds the boundary layer (as fill_interior). Rethrows the first
  /// error of work().
  InteriorFillStats finish(const SurfaceMesh& surface, SpacingGrid& grid, NodeSet& nodes,
                           const std::function<void(double)>& progress = {});

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace kdmesh
