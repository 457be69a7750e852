// kdmesh — how many nodes and how much memory a meshing job will need, before it runs
// (pipeline stage: PreparedSurface + SizingField -> ResourceEstimate).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <string>

#include "core/memory_amount.h"
#include "mesher/domain.h"

namespace kdmesh {

/// Node and memory estimate of one job.
struct ResourceEstimate {
  double surface_nodes = 0;    ///< integral over the surface of 1 / (kSurfaceDensity h^2)
  double interior_nodes = 0;   ///< integral over the solid of 1 / (kVolumeDensity h^3)
  double nodes = 0;            ///< their sum
  double peak_bytes = 0;       ///< peak resident memory of the whole pipeline (see below)
  bool capped = false;         ///< integration stopped at the cap: the true figures are larger
  std::uint64_t samples = 0;   ///< sizing-field and inside/outside queries made
};

/// Nodes per unit area / volume of the placement (mesher/placement/node_placement) where the size is h:
/// 1 / (kSurfaceDensity h^2) and 1 / (kVolumeDensity h^3). Calibrated on the shipped models
/// at default size (docs/robustness.md, "Memory"): there the node estimate is within 5%; at
/// the paper sizes it is 13-21% low (finer meshes place relatively more nodes).
inline constexpr double kSurfaceDensity = 0.70;
inline constexpr double kVolumeDensity = 0.94;
/// Peak resident bytes of `kdmesh mesh` per ESTIMATED node and per input facet, plus a fixed
/// base: fitted to /usr/bin/time -v on the shipped models at default and paper sizes, where
/// peak RSS / estimated nodes was 1270-1280 bytes on all four (docs/robustness.md, "Memory").
inline constexpr double kBytesPerNode = 1275;
inline constexpr double kBytesPerFacet = 400;
inline constexpr double kBaseBytes = 16e6;

/// Estimates the nodes the placement will make and the pipeline's peak memory, by adaptive
/// integration of the sizing field: facets are split until they are small against h; the
/// solid's bounding cube is split into octants until a cell is small against h, or lies
/// wholly inside (by the surface distance) where h varies little across it (by the field's
/// gradation bound). Runs on all cores; deterministic (the same figures on any thread count).
/// Its queries (`samples`) grow with the estimated nodes where the size varies: 0.84 per
/// estimated node on pinion.ply at 1M tets, 4.0 on the paper gear box, 12-16 on the thin walls
/// of femur.ply and occt_sh2.stl at diag/20 (cells near a wall refine to about 2 h). Stops
/// early, with `capped` set, once the node estimate passes `node_cap` (so absurd sizes are
/// refused fast): the figures are then those of node_cap nodes, a lower bound.
ResourceEstimate estimate_resources(const Domain& domain, double node_cap = 2e9);

}  // namespace kdmesh
