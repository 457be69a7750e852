// kdmesh — Wavefront OBJ surface reader (our own; why not OpenMesh's: io/surface_io.cpp).
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// What is read: 'v x y z [...]' lines (the first three numbers; a w or vertex colours after
// them are ignored) and 'f' lines (also the old spelling 'fo') whose references are v, v/vt,
// v//vn or v/vt/vn: only v matters. Indices are 1-based; a negative one counts back from the
// last vertex defined before the line (-1 is that vertex). A positive index may name a vertex
// defined later in the file, as OpenMesh's reader and most others allow. Every other statement
// (vt, vn, vp, o, g, s, usemtl, mtllib, l, p, free-form curves and surfaces) carries no facet
// of the surface and is skipped. '#' starts a comment; CRLF line ends and a UTF-8 byte order
// mark are accepted. A '\' line continuation is not supported (the '\' is reported as a bad
// vertex reference, naming the line).
//
// The faces are kept exactly as the file has them (file order, orientation, repeated or
// degenerate faces included): prepare_surface names their defects as it does for STL and PLY.
// A polygon of more than 3 vertices is triangulated as PLY's are (io/polygon_faces.h: its fan
// from the first vertex when convex, ear clipping in its plane otherwise); vertices are welded
// by bit-identical coordinates as every reader does (io/point_welder.h), so a surface gives the
// same SurfaceMesh from OBJ as from PLY.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.h"
#include "io/file_io.h"
#include "io/point_welder.h"
#include "io/polygon_faces.h"
#include "io/surface_io.h"
#include "io/text_lines.h"

namespace kdmesh {

namespace {

/// The vertex count of the file: the 'v' lines. Counted first so that the coordinates are
/// allocated once, from lines that exist (OBJ has no header count that could lie).
std::uint64_t count_vertex_lines(std::string_view text) {
  std::uint64_t n = 0;
  TextLines lines(text);
  while (lines.next())
    if (lines.token() == "v") ++n;
  return n;
}

/// Appends the coordinates of the 'v' line being read (the first three numbers) to `raw`.
void read_vertex(const std::string& path, TextLines& lines, std::vector<double>& raw) {
  const std::uint64_t vertex = raw.size() / 3 + 1;
  for (int c = 0; c < 3; ++c) {
    const std::string_view t = lines.token();
    double v;
    if (!parse_whole_token(t, v))
      throw InputError(path, lines.number(),
                       "vertex " + std::to_string(vertex) + " (1-based): coordinate " + char('x' + c) + " " +
                           (t.empty() ? std::string("is missing") : quote_token_printable(t) + " is not a number"));
    if (!std::isfinite(v))
      throw InputError(path, lines.number(),
                       "vertex " + std::to_string(vertex) + " (1-based): non-finite coordinate " + char('x' + c) +
                           " = " + quote_token_printable(t));
    raw.push_back(v);
  }
}

/// The 0-based vertex of the face reference `ref` (v, v/vt, v//vn or v/vt/vn) on the current
/// line of face `face`; `defined` vertices precede the line, `total` are in the file.
std::uint32_t vertex_of_reference(const std::string& path, const TextLines& lines, std::string_view ref,
                                  std::uint64_t face, std::uint64_t defined, std::uint64_t total) {
  auto fail = [&](const std::string& what) {
    return InputError(path, lines.number(), "face " + std::to_string(face) + " (0-based): " + what);
  };
  std::int64_t i;
  if (!parse_whole_token(ref.substr(0, ref.find('/')), i))
    throw fail("vertex reference " + quote_token_printable(ref) +
               " is not an index (expected v, v/vt, v//vn or v/vt/vn, v a non-zero integer)");
  if (i == 0) throw fail("vertex index 0 is out of range (OBJ indices start at 1)");
  if (i > 0) {
    if (std::uint64_t(i) > total)
      throw fail("vertex index " + std::to_string(i) + " is out of range (the file has " + std::to_string(total) +
                 " vertices; OBJ indices are 1-based)");
    return std::uint32_t(i - 1);
  }
  const std::uint64_t back = std::uint64_t(-(i + 1)) + 1;  // |i| without overflow at INT64_MIN
  if (back > defined)
    throw fail("relative vertex index " + std::to_string(i) + " is out of range (only " + std::to_string(defined) +
               " vertices are defined before this line)");
  return std::uint32_t(defined - back);
}

}  // namespace

SurfaceMesh read_obj(const std::string& path) {
  const std::string data = read_whole_file(path);
  if (data.empty()) throw InputError(path, 0, "empty file");
  std::string_view text = data;
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);  // UTF-8 byte order mark

  const std::uint64_t total = count_vertex_lines(text);
  if (total > 0xFFFFFFFFull) throw InputError(path, 0, "more than 2^32-1 vertices");
  std::vector<double> raw;
  // A valid 'v' line takes at least 7 bytes ("v 0 0 0"): a file of bare "v" lines, which fails
  // at its first one, cannot make this reserve more than a valid file of its size would.
  raw.reserve(3 * std::min<std::uint64_t>(total, text.size() / 7 + 1));
  SurfaceMesh mesh;
  FaceSink sink{path, total, mesh.tris, {}, {}, {}};
  auto where = [] { return std::string(); };  // the line number says where
  std::uint64_t face = 0;
  TextLines lines(text);
  while (lines.next()) {
    const std::string_view key = lines.token();
    if (key == "v") {
      read_vertex(path, lines, raw);
    } else if (key == "f" || key == "fo") {
      for (std::string_view ref = lines.token(); !ref.empty(); ref = lines.token())
        sink.index(vertex_of_reference(path, lines, ref, face, raw.size() / 3, total), face, lines.number(), where);
      sink.finish(face, lines.number(), where);
      ++face;
    }
  }
  if (face == 0) throw InputError(path, 0, "no faces ('f' lines): a point cloud, not a surface");
  if (mesh.tris.size() / 3 > 0xFFFFFFFFull) throw InputError(path, 0, "more than 2^32-1 triangles");
  sink.triangulate_polygons(raw);
  weld_file_vertices(raw, mesh);
  return mesh;
}

}  // namespace kdmesh
