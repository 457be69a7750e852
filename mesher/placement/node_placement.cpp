// kdmesh — node placement: corners, feature edges, surface, interior.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/placement/node_placement.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <system_error>
#include <thread>

#include "core/error.h"
#include "core/timer.h"
#include "mesher/placement/edge_sampling.h"
#include "mesher/placement/interior_fill.h"
#include "mesher/placement/spacing_grid.h"
#include "mesher/placement/surface_sampling.h"
#include "mesher/surface/surface_bodies.h"

namespace kdmesh {

namespace {

// Calibration, measured with tools/bench/bench_placement --fidelity (Delaunay of the nodes,
// tets with centroid inside, edge length / h at the edge midpoint):
//  - surface: nodes keep kSurfaceBeta * (h_p + h_q) / 2 apart. 0.7 puts 97.7% of the
//    surface-surface edges of a box in [0.7, 1.4] h (mean 0.99); 0.75 gave 92% (mean 1.06).
//  - interior: a BCC lattice of cube edge 1.083 h (InteriorFillOptions::kappa: mean Delaunay
//    edge 0.9234 a = h); kInteriorBeta only separates it from surface nodes and other levels.
//  - clearance (PlacementOptions::interior_clearance, default 0.8): a surface Delaunay
//    triangle's diametral ball is centred on the surface with its circumradius R as radius,
//    and with maximal Poisson-disk sampling of spacing 0.7 h no surface point is farther
//    than ~0.7 h from a node, so R <~ 0.7 h; interior nodes at >= 0.8 h stay outside every
//    such ball. Smaller values shorten the surface-interior edges (0.5: 72% of them in range
//    instead of 62%) but give up that margin.
constexpr double kSurfaceBeta = 0.7;
// Feature (edge) nodes keep kFeatureBeta * (h_p + h_q) / 2 from the corners and from the nodes
// of other feature curves (place_edge_nodes). Measured on the 78 real-part cases (26 parts x
// diag/20, /40, /80): 0 (every node kept) left 12 meshes with a tet under 5 deg; 0.3 left 6
// and raised the meshes with min >= 12 deg from 54 to 58; 0.5 left 6 but lowered them to 52
// (fewer feature nodes where the curves run side by side). Below the surface rule's 0.7: a
// feature node dropped is a point of a sharp curve the mesh no longer holds.
constexpr double kFeatureBeta = 0.3;
constexpr double kInteriorBeta = 0.75;

}  // namespace

NodeSet place_nodes(const Domain& domain, const FeatureEdges& features,
                    const PlacementOptions& options, PlacementStats* stats) {
  const PreparedSurface& surface = domain.surface;
  const SurfaceQuery& query = domain.query;
  const SizingField& sizing = domain.sizing;
  if (!(options.interior_clearance >= 0) || !std::isfinite(options.interior_clearance))
    throw UsageError("node placement: interior_clearance must be a finite number >= 0, not " +
                     std::to_string(options.interior_clearance));
  const SurfaceMesh& mesh = surface.mesh;
  if (mesh.num_tris() == 0) throw GeometryError("node placement: the surface has no facets");
  if (!(sizing.max_size() > 0))
    throw UsageError("node placement: the sizing field has no positive max_size");
  auto progress = [&](const char* stage, double f) {
    if (options.progress) options.progress(stage, f);
  };

  // Bounding box of the surface points (the prepared bbox may be unset in hand-built input).
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (std::size_t i = 0; i < mesh.points.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], mesh.points.p(std::uint32_t(i))[a]);
      hi[a] = std::max(hi[a], mesh.points.p(std::uint32_t(i))[a]);
    }
  double extent = 0;
  for (int a = 0; a < 3; ++a) extent = std::max(extent, hi[a] - lo[a]);
  if (!(extent > 0) || !std::isfinite(extent))
    throw GeometryError("node placement: the surface has an empty or non-finite bounding box");

  // Finest grid cell: h_min, but at most 2^17 cells across the box (the grid's key range).
  const double s0 = std::max(sizing.min_size() > 0 ? sizing.min_size() : sizing.max_size(),
                             std::ldexp(extent, -17));
  const double glo[3] = {lo[0] - extent, lo[1] - extent, lo[2] - extent};
  SpacingGrid grid(glo, s0);
  grid.set_lipschitz(sizing.options().gradation);
  NodeSet nodes;

  InteriorFillOptions io;
  io.beta = kInteriorBeta;
  io.clearance = options.interior_clearance;
  io.seed = options.seed;
  const BodyInterfaces& ifc = surface.interfaces;
  const std::size_t n_outer = mesh.num_tris(), n_ifc = ifc.mesh.num_tris();
  // Touching bodies: the fill sees one surface, the outer facets, then each interface facet in
  // both orientations (the pair leaves the ray parity of the union unchanged), ids n_outer + f
  // and n_outer + n_ifc + f.
  Stopwatch interface_clock;
  std::unique_ptr<SurfaceMesh> all;
  std::unique_ptr<const SurfaceQuery> all_query;
  if (!ifc.empty()) {
    all = std::make_unique<SurfaceMesh>(mesh);
    const std::uint32_t off = std::uint32_t(all->points.size());
    all->points.xyz.insert(all->points.xyz.end(), ifc.mesh.points.xyz.begin(), ifc.mesh.points.xyz.end());
    for (int side = 0; side < 2; ++side)
      for (std::size_t f = 0; f < n_ifc; ++f) {
        const std::uint32_t* t = ifc.mesh.tri(f);
        all->tris.insert(all->tris.end(), {t[0] + off, side ? t[2] + off : t[1] + off, side ? t[1] + off : t[2] + off});
      }
    all_query = std::make_unique<const SurfaceQuery>(*all);
    io.two_sided_from = std::uint32_t(n_outer);
  }
  if (stats) stats->interface_seconds += interface_clock.seconds();
  // The interior lattice's candidates depend on the surface and the field only, not on the
  // nodes placed before them: a helper thread generates them while this one samples the
  // feature edges and the surface, which run on one thread (8.5 s of the paper gear box's
  // placement, the second core idle). The nodes are the same either way.
  InteriorLattice lattice(lo, hi, all_query ? *all_query : query, sizing, io);
  struct Helper {  // joined on every path; told to stop first if the sampling throws
    InteriorLattice& lattice;
    std::thread thread;
    ~Helper() {
      if (!thread.joinable()) return;
      lattice.stop();
      thread.join();
    }
  } helper{lattice, {}};
  if (io.threads > 1) {
    try {
      helper.thread = std::thread([&lattice] { lattice.work(); });
    } catch (const std::system_error&) {
      // No thread (a limit on processes and threads): the lattice is generated below, here.
    }
  }

  progress("edges", 0);
  SpacingGrid feature_balls(glo, s0);
  place_edge_nodes(mesh, features, sizing, kFeatureBeta, grid, nodes, &feature_balls);
  progress("edges", 1);

  SurfaceSamplingOptions so;
  so.seed = options.seed;
  so.beta = kSurfaceBeta;
  place_surface_nodes(mesh, sizing, so, grid, nodes, [&](double f) { progress("surface", f); }, &feature_balls);

  // The interfaces are sampled like the surface (after it, so their rims reuse the outer
  // surface's feature nodes), and the interior keeps clear of them too.
  const std::size_t first = nodes.size_count();
  if (!ifc.empty()) {
    interface_clock.reset();
    const FeatureEdges inner =
        detect_sharp_edges(ifc.mesh, 0, interface_inner_edges(surface, options.interface_feature_angle));
    place_edge_nodes(ifc.mesh, inner, sizing, kFeatureBeta, grid, nodes, &feature_balls, true);
    place_surface_nodes(ifc.mesh, sizing, so, grid, nodes, [&](double f) { progress("interfaces", f); }, &feature_balls);
    for (std::size_t i = first; i < nodes.size_count(); ++i) nodes.facet[i] += std::uint32_t(n_outer);
    if (stats) stats->interface_seconds += interface_clock.seconds();
  }

  progress("interior", 0);
  // The calling thread and the helper (if any) take the blocks left, with more threads if
  // io.threads asks for them.
  lattice.work_on(std::max(1u, io.threads) - (helper.thread.joinable() ? 1 : 0));
  if (helper.thread.joinable()) helper.thread.join();
  progress("interior", 0.5);
  lattice.finish(all ? *all : mesh, grid, nodes, [&](double f) { progress("interior", f); });
  if (!ifc.empty())  // interface nodes name no facet of the outer surface
    for (std::size_t i = first; i < nodes.size_count(); ++i)
      if (nodes.kind[i] != NodeKind::interior) nodes.facet[i] = kNoFacet;
  return nodes;
}

}  // namespace kdmesh
