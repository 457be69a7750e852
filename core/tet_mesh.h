// kdmesh — tetrahedralizations as plain flat arrays.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/point_set.h"
#include "core/uninit_allocator.h"

namespace kdmesh {

/// Id of the "infinite" vertex that closes the convex hull in a Triangulation.
inline constexpr std::uint32_t kInfiniteVertex = std::numeric_limits<std::uint32_t>::max();

/// A full Delaunay triangulation of a point set, closed by an infinite vertex
/// (the kernel's native form; what the validity checker reads).
///
/// Each tet is one 32-byte record of 8 uint32 in `data`: its vertices v(t,0..3) (point ids, or
/// kInfiniteVertex), then its neighbours adj(t,0..3). Keeping both in one record means a
/// cavity step touches one cache line, not two arrays.
///  - Face i of tet t is the face opposite v(t,i).
///  - adj(t,i) = 4*u + j means: face i of t is face j of tet u ("face reference").
///  - Finite tets are positively oriented: det[v1-v0, v2-v0, v3-v0] > 0, i.e. v3 lies on the
///    side of plane (v0,v1,v2) that (v1-v0)x(v2-v0) points to; (0, e1, e2, e3) is positive.
///    This is VTK_TETRA's convention and kdmesh's everywhere (mesher/delaunay/predicates.h: orient3d).
///  - An infinite tet has exactly one infinite vertex; replacing it by a point far outside the
///    hull across its finite face gives a positively oriented tet.
/// Every tet in the arrays is alive (no holes).
/// The records of a Triangulation: resize(n) leaves new records unwritten (UninitAllocator).
using TetRecords = std::vector<std::uint32_t, UninitAllocator<std::uint32_t>>;

struct Triangulation {
  TetRecords data;  ///< 8 per tet: v0 v1 v2 v3 adj0 adj1 adj2 adj3

  std::size_t num_tets() const { return data.size() / 8; }
  std::uint32_t v(std::size_t t, int i) const { return data[8 * t + i]; }
  std::uint32_t adj(std::size_t t, int i) const { return data[8 * t + 4 + i]; }
  std::uint32_t& v(std::size_t t, int i) { return data[8 * t + i]; }
  std::uint32_t& adj(std::size_t t, int i) { return data[8 * t + 4 + i]; }
  /// The vertex opposite face reference f = 4*u + j, i.e. v(u, j).
  std::uint32_t opposite(std::uint32_t f) const { return data[8 * std::size_t(f >> 2) + (f & 3)]; }
  bool is_infinite(std::size_t t) const {
    const std::uint32_t* x = &data[8 * t];
    return x[0] == kInfiniteVertex || x[1] == kInfiniteVertex || x[2] == kInfiniteVertex ||
           x[3] == kInfiniteVertex;
  }
};

/// A named per-point or per-cell data array for writers (one component per entry): 64-bit
/// reals, else 32-bit floats, else ints, whichever is not empty first.
struct DataArray {
  std::string name;
  std::vector<std::int32_t> ints;   ///< used when `reals` and `floats` are empty
  std::vector<double> reals;
  std::vector<float> floats = {};   ///< used when `reals` is empty (VTU: Float32)
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
