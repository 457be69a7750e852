// kdmesh — faces of indexed surface formats (PLY, OBJ, OFF): vertex indices collected face
// by face, polygons triangulated in their plane (internal to io/).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/error.h"

namespace kdmesh {

/// Triangulates the polygon `poly` (point ids into `xyz`, 3 doubles each) by ear clipping in
/// its plane (projected along the largest component of its Newell normal), appending n - 2
/// triangles with the polygon's orientation to `out`. A convex polygon gives its fan from the
/// first vertex. False (nothing appended) when no ear is found: a self-intersecting or
/// degenerate polygon.
bool ear_clip(const std::vector<std::uint32_t>& poly, const std::vector<double>& xyz, std::uint32_t* out);

/// Collects faces (file vertex indices) and fan-triangulates them into `tris`; polygons of
/// more than 3 vertices are remembered, to be triangulated properly (ear_clip) once the
/// vertices are known.
struct FaceSink {
  const std::string& path;
  std::uint64_t num_vertices;
  std::vector<std::uint32_t>& tris;
  std::vector<std::uint32_t> poly;
  struct Polygon {
    std::size_t first_tri;  ///< offset in tris of its fan
    std::size_t begin, end; ///< its vertices in `polygon_vertices`
  };
  std::vector<Polygon> polygons;
  std::vector<std::uint32_t> polygon_vertices;

  /// Replaces each remembered polygon's fan by its ear-clipped triangulation (kept when the
  /// polygon has no ear: prepare_surface then reports the fan's defects).
  void triangulate_polygons(const std::vector<double>& xyz) {
    std::vector<std::uint32_t> ring;
    for (const Polygon& p : polygons) {
      ring.assign(polygon_vertices.begin() + long(p.begin), polygon_vertices.begin() + long(p.end));
      std::vector<std::uint32_t> out(3 * (ring.size() - 2));
      if (ear_clip(ring, xyz, out.data())) std::copy(out.begin(), out.end(), tris.begin() + long(p.first_tri));
    }
  }

  /// `where`: "line N" / "byte offset N" context for messages (built lazily by the caller).
  template <class Where>
  void finish(std::uint64_t face, std::uint64_t line, Where where) {
    if (poly.size() < 3)
      throw InputError(path, line,
                       "face " + std::to_string(face) + " (0-based" + where() + ") has " +
                           std::to_string(poly.size()) + " vertices; at least 3 are needed");
    if (poly.size() > 3) {
      polygons.push_back({tris.size(), polygon_vertices.size(), polygon_vertices.size() + poly.size()});
      polygon_vertices.insert(polygon_vertices.end(), poly.begin(), poly.end());
    }
    for (std::size_t k = 1; k + 1 < poly.size(); ++k) {
      tris.push_back(poly[0]);
      tris.push_back(poly[k]);
      tris.push_back(poly[k + 1]);
    }
    poly.clear();
  }
  template <class Where>
  void index(std::int64_t v, std::uint64_t face, std::uint64_t line, Where where) {
    if (v < 0 || std::uint64_t(v) >= num_vertices)
      throw InputError(path, line,
                       "face " + std::to_string(face) + " (0-based" + where() +
                           "): vertex index " + std::to_string(v) + " is out of range (" +
                           std::to_string(num_vertices) + " vertices)");
    poly.push_back(std::uint32_t(v));
  }
};

}  // namespace kdmesh
