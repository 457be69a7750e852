// kdmesh — verify a Delaunay tetrahedralization three ways: the exact validity check, then
// TetGen 1.5 and CGAL 5.5 on the same points (what `delaunay --check` and jobs' checks run).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/point_set.h"
#include "core/tet_mesh.h"

namespace kdmesh {

struct DelaunayVerifyOptions {
  /// Compare with the reference kernels (TetGen 1.5, then CGAL 5.5 or the kdmesh kernel).
  /// The exact validity check always runs: its tie count decides how the comparisons judge.
  bool references = true;
  /// The tets came from CGAL: compare with the kdmesh kernel (kd-bfs, `seed`) instead of CGAL.
  bool compare_kdmesh_kernel = false;
  std::uint64_t seed = 1;
  /// Called as each check starts ("check: TetGen 1.5", ...); may be empty.
  std::function<void(const std::string&)> stage;
};

struct DelaunayVerification {
  bool pass = false;
  /// {pass, general_position, validity {...}, tetgen {...}, cgal|kdmesh {...}}
  nlohmann::json json;
  std::string report;  ///< human-readable lines ("check:\n  validity ok ...\n")
};

/// `tri`: the triangulation of `points` (kernel form, for the exact checker); `canon_tets`: its
/// finite tets in canonical ids (tet_compare.h: canonical_point_ids).
/// In general position (no perturbation-only ties) the Delaunay tetrahedralization is unique,
/// so the tet sets must be identical; otherwise only the volumes must agree (1e-9 relative).
/// Input TetGen 1.5 refuses (GeometryError) makes that comparison "skipped", not failed.
DelaunayVerification verify_delaunay(const PointSet& points, const Triangulation& tri,
                                     const std::vector<std::uint32_t>& canon_tets,
                                     const DelaunayVerifyOptions& options = {});

}  // namespace kdmesh
