// kdmesh — OFF (Object File Format) surface reader (our own; why not OpenMesh's:
// io/surface_io.cpp).
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// What is read: the ascii OFF of Geomview and most exporters. A header keyword OFF, optionally
// with the prefixes ST, C and N (texture coordinates, colours and normals after each vertex's
// x y z: read past), then the counts "vertices faces [edges]" (on the keyword's line or the
// next one; the edge count is ignored), then one vertex per line (x y z first) and one face per
// line ("n i1 ... in", 0-based indices; a face colour after them is read past). ModelNet's
// "OFF490 518 0" (no blank after the keyword) is read as "OFF 490 518 0". '#' starts a
// comment; blank lines, CRLF line ends and a UTF-8 byte order mark are accepted.
// Refused with an InputError naming the line: binary OFF, 4OFF and nOFF (homogeneous or
// n-dimensional vertices), counts the rest of the file cannot hold (checked BEFORE anything is
// allocated from them), missing or extra records, indices out of range.
//
// The faces are kept exactly as the file has them; polygons are triangulated and vertices
// welded as for PLY (io/polygon_faces.h, io/point_welder.h), so a surface gives the same
// SurfaceMesh from OFF as from PLY, and prepare_surface names its defects the same way.
#include <algorithm>
#include <cctype>
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

/// Checks the header keyword [ST][C][N]OFF on the current line ("OFF" in any case; the
/// prefixes as Geomview spells them, where 'N' is normals but 'n' is a dimension).
void check_off_keyword(const std::string& path, const TextLines& lines, std::string_view key) {
  auto upper = [](char c) { return char(std::toupper(static_cast<unsigned char>(c))); };
  const bool off = key.size() >= 3 && upper(key[key.size() - 3]) == 'O' && upper(key[key.size() - 2]) == 'F' &&
                   upper(key[key.size() - 1]) == 'F';
  if (!off)
    throw InputError(path, lines.number(),
                     "not an OFF file: expected the keyword 'OFF' (or COFF, NOFF, STOFF, ...), found " +
                         (key.empty() ? std::string("nothing") : quote_token_printable(key)));
  const std::string_view prefix = key.substr(0, key.size() - 3);
  if (prefix.find_first_of("4n") != std::string_view::npos)
    throw InputError(path, lines.number(),
                     quote_token_printable(key) + ": 4OFF and nOFF (homogeneous or n-dimensional vertices) are not supported");
  if (prefix.find_first_not_of("STCN") != std::string_view::npos)
    throw InputError(path, lines.number(), "not an OFF file: unknown header keyword " + quote_token_printable(key));
}

/// The header count `t` (on the current line), or InputError naming `what`.
std::uint64_t header_count(const std::string& path, const TextLines& lines, std::string_view t, const char* what) {
  std::uint64_t n;
  if (!parse_whole_token(t, n))
    throw InputError(path, lines.number(),
                     std::string("OFF header: the ") + what + " count " +
                         (t.empty() ? std::string("is missing") : quote_token_printable(t) + " is not a non-negative integer") +
                         " (expected 'vertices faces edges')");
  return n;
}

/// Reads the vertex lines into `raw` (3 doubles each, allocated by the caller).
void read_off_vertices(const std::string& path, TextLines& lines, std::vector<double>& raw) {
  const std::size_t nv = raw.size() / 3;
  for (std::size_t i = 0; i < nv; ++i) {
    if (!lines.next_nonblank())
      throw InputError(path, lines.number(),
                       "unexpected end of file: vertex " + std::to_string(i) + " (0-based) of the " +
                           std::to_string(nv) + " the header declares is missing");
    for (int c = 0; c < 3; ++c) {
      const std::string_view t = lines.token();
      double v;
      if (!parse_whole_token(t, v))
        throw InputError(path, lines.number(),
                         "vertex " + std::to_string(i) + " (0-based): coordinate " + char('x' + c) + " " +
                             (t.empty() ? std::string("is missing") : quote_token_printable(t) + " is not a number"));
      if (!std::isfinite(v))
        throw InputError(path, lines.number(),
                         "vertex " + std::to_string(i) + " (0-based): non-finite coordinate " + char('x' + c) +
                             " = " + quote_token_printable(t));
      raw[3 * i + std::size_t(c)] = v;
    }
  }
}

/// Reads `nf` face lines into `sink`.
void read_off_faces(const std::string& path, TextLines& lines, std::uint64_t nf, FaceSink& sink) {
  auto where = [] { return std::string(); };  // the line number says where
  for (std::uint64_t f = 0; f < nf; ++f) {
    if (!lines.next_nonblank())
      throw InputError(path, lines.number(),
                       "unexpected end of file: face " + std::to_string(f) + " (0-based) of the " +
                           std::to_string(nf) + " the header declares is missing");
    const std::string_view t = lines.token();
    std::uint64_t n;
    if (!parse_whole_token(t, n))
      throw InputError(path, lines.number(),
                       "face " + std::to_string(f) + " (0-based): vertex count " + quote_token_printable(t) +
                           " is not a non-negative integer");
    for (std::uint64_t k = 0; k < n; ++k) {
      const std::string_view ix = lines.token();
      std::int64_t v;
      if (ix.empty())
        throw InputError(path, lines.number(),
                         "face " + std::to_string(f) + " (0-based) declares " + std::to_string(n) +
                             " vertices, but the line holds " + std::to_string(k));
      if (!parse_whole_token(ix, v))
        throw InputError(path, lines.number(),
                         "face " + std::to_string(f) + " (0-based): vertex index " + quote_token_printable(ix) +
                             " is not an integer");
      sink.index(v, f, lines.number(), where);
    }
    sink.finish(f, lines.number(), where);
  }
}

}  // namespace

SurfaceMesh read_off(const std::string& path) {
  const std::string data = read_whole_file(path);
  if (data.empty()) throw InputError(path, 0, "empty file");
  std::string_view text = data;
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);  // UTF-8 byte order mark

  TextLines lines(text);
  if (!lines.next_nonblank()) throw InputError(path, lines.number(), "not an OFF file: no 'OFF' keyword");
  std::string_view key = lines.token(), first;
  // "OFF490 518 0": the keyword and the vertex count run together in every OFF file of the
  // ModelNet data sets; the digits are the count.
  if (key.size() > 3 && (key[0] == 'O' || key[0] == 'o') && key.find_first_not_of("0123456789", 3) == std::string_view::npos) {
    first = key.substr(3);
    key = key.substr(0, 3);
  }
  check_off_keyword(path, lines, key);
  // The counts follow the keyword on its line (some writers) or start the next line.
  if (first.empty()) first = lines.token();
  if (first == "BINARY" || first == "binary")
    throw InputError(path, lines.number(), "binary OFF is not supported (only ascii OFF)");
  if (first.empty()) {
    if (!lines.next_nonblank())
      throw InputError(path, lines.number(), "OFF header: the counts 'vertices faces edges' are missing");
    first = lines.token();
  }
  const std::uint64_t nv = header_count(path, lines, first, "vertex");
  const std::uint64_t nf = header_count(path, lines, lines.token(), "face");
  const std::uint64_t header_line = lines.number();

  // Counts the file cannot hold are refused before anything is allocated from them: a vertex
  // line takes at least 6 bytes ("0 0 0\n"), a face line at least 8 ("3 0 1 2\n"), the last
  // line may lack its newline.
  const std::uint64_t left = lines.remaining();
  if (nv > left || nf > left || 6 * nv + 8 * nf > left + 1)
    throw InputError(path, header_line,
                     "the header declares " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                         " faces, but only " + std::to_string(left) +
                         " bytes follow (at least 6 per vertex line and 8 per face line are needed): "
                         "truncated file or wrong counts");
  if (nv > 0xFFFFFFFFull) throw InputError(path, header_line, "more than 2^32-1 vertices");
  if (nf == 0) throw InputError(path, header_line, "no faces: a point cloud, not a surface");

  std::vector<double> raw(3 * nv);
  SurfaceMesh mesh;
  mesh.tris.reserve(3 * nf);
  FaceSink sink{path, nv, mesh.tris, {}, {}, {}};
  read_off_vertices(path, lines, raw);
  read_off_faces(path, lines, nf, sink);
  if (lines.next_nonblank())
    throw InputError(path, lines.number(),
                     "unexpected data after the last of the " + std::to_string(nf) +
                         " faces the header declares (a wrong face count?)");
  if (mesh.tris.size() / 3 > 0xFFFFFFFFull) throw InputError(path, 0, "more than 2^32-1 triangles");
  sink.triangulate_polygons(raw);
  weld_file_vertices(raw, mesh);
  return mesh;
}

}  // namespace kdmesh
