// kdmesh — welding of surface points with bit-identical coordinates, shared by every surface
// reader so that STL, PLY, OBJ and OFF give the same points for the same coordinates
// (internal to io/).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <bit>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "core/point_set.h"
#include "core/surface_mesh.h"

namespace kdmesh {

/// Maps coordinates to point ids; identical coordinates (bitwise, -0.0 == +0.0) share an id.
/// Open addressing (O(n)); add() stays in the header so the binary STL loop inlines it.
class PointWelder {
 public:
  explicit PointWelder(PointSet& out, std::size_t expected) : out_(out) {
    std::size_t cap = 16;
    while (cap < 2 * expected) cap *= 2;
    slots_.assign(cap, kEmpty);
    out_.xyz.reserve(3 * expected);
  }

  std::uint32_t add(double x, double y, double z) {
    const std::uint64_t k[3] = {bits(x), bits(y), bits(z)};
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = hash(k) & mask;; i = (i + 1) & mask) {
      const std::uint32_t id = slots_[i];
      if (id == kEmpty) {
        const std::size_t n = out_.size();
        if (n >= kEmpty) throw std::length_error("more than 2^32-1 distinct points");
        out_.push_back(x == 0 ? 0.0 : x, y == 0 ? 0.0 : y, z == 0 ? 0.0 : z);
        slots_[i] = std::uint32_t(n);
        if (2 * (n + 1) > slots_.size()) grow();
        return std::uint32_t(n);
      }
      const double* p = out_.p(id);
      if (bits(p[0]) == k[0] && bits(p[1]) == k[1] && bits(p[2]) == k[2]) return id;
    }
  }

 private:
  static constexpr std::uint32_t kEmpty = 0xFFFFFFFFu;
  static std::uint64_t bits(double v) { return std::bit_cast<std::uint64_t>(v == 0 ? 0.0 : v); }
  static std::uint64_t hash(const std::uint64_t k[3]) {
    std::uint64_t h = k[0] * 0x9E3779B97F4A7C15ull;
    h ^= (h >> 29) ^ (k[1] * 0xC2B2AE3D27D4EB4Full);
    h ^= (h >> 31) ^ (k[2] * 0x165667B19E3779F9ull);
    return h ^ (h >> 33);
  }
  void grow();

  PointSet& out_;
  std::vector<std::uint32_t> slots_;
};

/// Welds `raw` (3 doubles per file vertex, in file order) into `mesh.points` and renumbers
/// `mesh.tris` (file vertex indices, all < raw.size() / 3) to the welded ids. Points no facet
/// uses are kept: the point ids are the welded file order; prepare_surface decides what unused
/// points mean.
void weld_file_vertices(const std::vector<double>& raw, SurfaceMesh& mesh);

}  // namespace kdmesh
