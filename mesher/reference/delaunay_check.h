// kdmesh — exact validity check of a Delaunay triangulation.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/point_set.h"
#include "core/tet_mesh.h"

namespace kdmesh {

struct ValidityReport {
  std::size_t finite_tets = 0;
  std::size_t hull_faces = 0;
  std::size_t asymmetric_adjacencies = 0;  ///< adj[adj[f]] != f or the shared face differs
  std::size_t bad_orientation = 0;         ///< finite tets with orient3d <= 0
  std::size_t non_delaunay_faces = 0;      ///< faces whose opposite vertex is in conflict (exact)
  /// Faces decided only by the symbolic perturbation: the opposite vertex lies exactly on the
  /// circumsphere (or in the plane and on the circumcircle of a hull face). When this is 0,
  /// the Delaunay tetrahedralization is unique and every correct kernel must return it.
  std::size_t tie_faces = 0;
  double volume = 0;       ///< sum of finite tet volumes (inf when beyond double range)
  double hull_volume = 0;  ///< convex hull volume from an independent computation (CGAL)
  /// The same two at scale 2^volume_exponent (magnitude_scale_exponent: the largest
  /// coordinate in [0.5, 1)), where they were compared: volume = scaled_volume * 2^(-3 k).
  double scaled_volume = 0, scaled_hull_volume = 0;
  int volume_exponent = 0;
  bool volume_matches = false;
  std::vector<std::string> problems;  ///< the first few faults, naming tets and point ids

  bool ok() const {
    return asymmetric_adjacencies == 0 && bad_orientation == 0 && non_delaunay_faces == 0 &&
           volume_matches;
  }
};

/// Checks, exactly: adjacency symmetry; positive orientation of finite tets; every face locally
/// Delaunay under the kernel's perturbed insphere (hull faces: convexity); and the total volume
/// against the convex hull's. Reports at most `max_problems` fault descriptions.
ValidityReport check_delaunay(const PointSet& points, const Triangulation& tri,
                              std::size_t max_problems = 10);

}  // namespace kdmesh
