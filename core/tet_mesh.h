// kdmesh — tetrahedralizations as plain flat arrays.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/point_set.h"

namespace kdmesh {

/// Id of the "infinite" vertex that closes the convex hull in a Triangulation.
inline constexpr std::uint32_t kInfiniteVertex = std::numeric_limits<std::uint32_t>::max();

/// A full Delaunay triangulation of a point set, closed by an infinite vertex
/// (the kernel's native form; what the validity checker reads).
///
/// Tet t has vertices v[4t+0..3] (point ids, or kInfiniteVertex) and neighbours adj[4t+0..3].
///  - Face i of tet t is the face opposite v[4t+i].
///  - adj[4t+i] = 4*u + j means: face i of t is face j of tet u.
///  - Finite tets are positively oriented: det[v1-v0, v2-v0, v3-v0] > 0, i.e. v3 lies on the
///    side of plane (v0,v1,v2) that (v1-v0)x(v2-v0) points to; (0, e1, e2, e3) is positive.
///    This is VTK_TETRA's convention and kdmesh's everywhere (mesher/predicates.h: orient3d).
///  - An infinite tet has exactly one infinite vertex; replacing it by a point far outside the
///    hull across its finite face gives a positively oriented tet.
/// Every tet in the arrays is alive (no holes).
struct Triangulation {
  std::vector<std::uint32_t> v;
  std::vector<std::uint32_t> adj;

  std::size_t num_tets() const { return v.size() / 4; }
  bool is_infinite(std::size_t t) const {
    return v[4 * t] == kInfiniteVertex || v[4 * t + 1] == kInfiniteVertex ||
           v[4 * t + 2] == kInfiniteVertex || v[4 * t + 3] == kInfiniteVertex;
  }
};

/// A named per-point or per-cell data array for writers (one component per entry).
struct DataArray {
  std::string name;
  std::vector<std::int32_t> ints;   ///< used when `reals` is empty
  std::vector<double> reals;
};

/// A finite tetrahedral mesh: what writers consume and what comparisons use.
/// tets[4t+0..3] are point ids, every tet positively oriented (see Triangulation).
struct TetMesh {
  PointSet points;
  std::vector<std::uint32_t> tets;
  std::vector<DataArray> point_data;
  std::vector<DataArray> cell_data;

  std::size_t num_tets() const { return tets.size() / 4; }
};

}  // namespace kdmesh
