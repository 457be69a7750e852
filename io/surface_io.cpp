// kdmesh — surface readers and writers: STL (ascii/binary) and PLY (ascii/binary LE/BE); the
// dispatch by extension to the OBJ and OFF readers (io/obj_reader.cpp, io/off_reader.cpp).
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Why every reader is our own and none is OpenMesh's (OpenMesh 9.0-4, Debian 12):
//   * OpenMesh's readers return a bool and print their reason to omerr; we need InputErrors
//     naming the file and the line (text) or facet/byte offset (binary). A custom
//     BaseImporter sees vertices and faces, not the reader's position in the file.
//   * STL/PLY. Its STL reader welds vertices itself, through a map of float vectors compared
//     with an epsilon (STLReader::set_epsilon), not by bit-identical coordinates (-0.0 == 0.0).
//     Its PLY reader hands the header's element counts to BaseImporter::reserve before any data
//     is read, so the sizes it trusts are the ones a lying header chooses; checking them
//     against the file size first would mean re-parsing the header ourselves anyway.
//     Measured with OpenMesh::IO::read_mesh into a TriMesh (2026-11-21): a binary STL that
//     declares 4,000,000,000 triangles and holds 1 returns true with 0 faces (a silent empty
//     result), and three facets on one edge return true with the edge split by duplicated
//     vertices (8 points instead of 5) and only "complex edge" on stderr.
//   * OBJ and OFF. Measured (2026-11-27) with a recording BaseImporter passed to
//     IOManager().read (what a custom importer would get) and with read_mesh into a TriMesh:
//       - both readers hand every vertex to add_vertex(Vec3f), never Vec3d: "v 0.1 0 0" arrives
//         as 0.10000000149011612, and the distinct vertices 1.00000001 and 1.00000002 both
//         arrive as 1, which the weld would then merge. Coordinates cannot be bit-identical to
//         the file's (nor to the same surface read from PLY), whatever the importer does;
//       - OBJ: "f 1 2 2" never reaches the importer (the reader drops it: 1 face of 2), so a
//         degenerate facet that prepare_surface names in STL/PLY would vanish; "f 1 2 9" with
//         4 vertices and "f 0 1 2" reach it as handles 8 and -1 with read() = true (the TriMesh
//         drops the face with "invalid vertex index" on stderr and returns true). Negative
//         indices, v/vt/vn references, comments and CRLF were read correctly. A non-manifold
//         edge reaches the importer raw (3 faces); the TriMesh splits it (8 points for 5);
//       - OFF: a face count of 40 over 4 face lines returns true with 40 faces (36 copies of
//         the last line); a face count of 4,000,000,000 calls reserve(nF = 4e9) and then keeps
//         producing phantom faces past the end of the file until std::bad_alloc (1.8 GB after
//         12 s under a 2 GB limit; the OOM killer without one), a vertex count of 4e8 likewise;
//         a comment line between "OFF" and the counts returns true with 0 vertices and 32,587
//         empty faces. Out-of-range indices reach the importer unchecked.
//     So the raw face list and exact coordinates are out of reach through OpenMesh, and the
//     counts would have to be parsed and checked by us before it runs: OBJ and OFF are read by
//     our own readers, with the same weld and polygon triangulation as PLY.
//   * .om (OpenMesh's binary format) is not read at all. It stores OpenMesh's half-edge
//     structure (a mesh OpenMesh has already repaired: it cannot hold a non-manifold edge), not
//     the raw faces the validation must see. And its reader trusts the file: measured on a
//     166-byte tetrahedron written by OpenMesh 9.0 and read into a PolyMesh with double points,
//     a face count of 4e9 ends in std::bad_alloc after 15 s; a file cut at 100 or 140 bytes
//     reads as true with 0 faces (and at 100, a wrong 4th vertex); one byte set to 0xFF at
//     offset 116 gives a heap-buffer-overflow write in ImporterT::set_next under AddressSanitizer
//     (with -DNDEBUG, as our Release builds; an assertion failure without it): of the 300 files
//     with one byte after the 16-byte header set to 0xFF or 0x7F, 28 overflow the heap. A custom
//     BaseImporter cannot take its place: with kernel() == nullptr the OM reader returns false.
// So every format is parsed from one in-memory copy of the file, every count is checked
// against the bytes that remain BEFORE anything is allocated from it, and errors are typed.
// kdmesh therefore does not link OpenMesh.
//
// Welding (io/point_welder.h): points with bit-identical coordinates (after mapping -0.0 to
// +0.0) become one point; facets keep file order and orientation.
#include "io/surface_io.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.h"
#include "io/file_io.h"
#include "io/ply_format.h"
#include "io/point_welder.h"
#include "io/polygon_faces.h"

namespace kdmesh {

namespace {

// ---------------------------------------------------------------------------------------------
// File input
// ---------------------------------------------------------------------------------------------

/// The file's bytes; an empty file is an error for every surface format.
std::string read_surface_file(const std::string& path) {
  std::string data = read_whole_file(path);
  if (data.empty()) throw InputError(path, 0, "empty file");
  return data;
}

// ---------------------------------------------------------------------------------------------
// Token scanning (ascii STL and ascii PLY data): whitespace-separated tokens with line numbers
// ---------------------------------------------------------------------------------------------

class Tokens {
 public:
  Tokens(std::string_view text, std::uint64_t first_line) : s_(text), line_(first_line) {}

  /// Next token, or an empty view at end of input. line() is the line of that token.
  std::string_view next() {
    while (pos_ < s_.size()) {
      const char c = s_[pos_];
      if (c == '\n') {
        ++line_;
        ++pos_;
      } else if (c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f') {
        ++pos_;
      } else {
        break;
      }
    }
    const std::size_t start = pos_;
    while (pos_ < s_.size()) {
      const char c = s_[pos_];
      if (c == '\n' || c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f') break;
      ++pos_;
    }
    return s_.substr(start, pos_ - start);
  }

  /// Skips the rest of the current line.
  void skip_line() {
    while (pos_ < s_.size() && s_[pos_] != '\n') ++pos_;
  }

  std::uint64_t line() const { return line_; }
  std::size_t remaining() const { return s_.size() - pos_; }

 private:
  std::string_view s_;
  std::size_t pos_ = 0;
  std::uint64_t line_;
};

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(a[i])) !=
        std::tolower(static_cast<unsigned char>(b[i])))
      return false;
  return true;
}

// ---------------------------------------------------------------------------------------------
// STL
// ---------------------------------------------------------------------------------------------

/// `u` with its bytes reversed (U: a 4- or 8-byte unsigned integer).
template <class U>
U bswap(U u) {
  if constexpr (sizeof(U) == 4)
    return __builtin_bswap32(u);
  else
    return __builtin_bswap64(u);
}

template <class T>
T load_le(const unsigned char* p) {
  using U = std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>;
  U u;
  std::memcpy(&u, p, sizeof u);
  if constexpr (std::endian::native == std::endian::big) u = bswap(u);
  return std::bit_cast<T>(u);
}

SurfaceMesh read_stl_binary(const std::string& path, std::string_view data) {
  const auto* base = reinterpret_cast<const unsigned char*>(data.data());
  const std::uint32_t count = load_le<std::uint32_t>(base + 80);
  SurfaceMesh mesh;
  mesh.tris.resize(3 * std::size_t(count));  // count was checked against the file size
  PointWelder weld(mesh.points, std::size_t(count) / 2 + 3);
  for (std::uint32_t f = 0; f < count; ++f) {
    const unsigned char* rec = base + 84 + 50 * std::size_t(f);
    for (int k = 0; k < 3; ++k) {
      const unsigned char* v = rec + 12 + 12 * k;
      const float x = load_le<float>(v), y = load_le<float>(v + 4), z = load_le<float>(v + 8);
      if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
        throw InputError(path, 0,
                         "facet " + std::to_string(f) + " (0-based, byte offset " +
                             std::to_string(v - base) + "): corner " + std::to_string(k) +
                             " has a non-finite coordinate");
      mesh.tris[3 * std::size_t(f) + k] = weld.add(x, y, z);
    }
  }
  return mesh;
}

SurfaceMesh read_stl_ascii(const std::string& path, std::string_view data) {
  Tokens tok(data, 1);
  SurfaceMesh mesh;
  // A facet takes well over 60 bytes of text ("facet normal 0 0 0 outer loop vertex 0 0 0 ...").
  PointWelder weld(mesh.points, data.size() / 120 + 3);
  mesh.tris.reserve(3 * (data.size() / 60 + 1));

  auto expect = [&](std::string_view want, const char* context) {
    const std::string_view t = tok.next();
    if (!iequals(t, want))
      throw InputError(path, tok.line(),
                       "expected '" + std::string(want) + "' " + context + ", found " +
                           (t.empty() ? std::string("end of file") : quote_token_printable(t)));
  };

  std::string_view t = tok.next();
  if (!iequals(t, "solid"))
    throw InputError(path, tok.line(), "not an STL file: ascii STL must start with 'solid'");
  tok.skip_line();  // solid name
  std::uint64_t facet = 0;
  for (;;) {
    t = tok.next();
    if (t.empty()) throw InputError(path, tok.line(), "unexpected end of file: no 'endsolid'");
    if (iequals(t, "endsolid")) {
      tok.skip_line();
      // Some exporters concatenate several solids in one file.
      t = tok.next();
      if (t.empty()) break;
      if (!iequals(t, "solid"))
        throw InputError(path, tok.line(), "expected 'solid' or end of file after 'endsolid', found " + quote_token_printable(t));
      tok.skip_line();
      continue;
    }
    if (!iequals(t, "facet"))
      throw InputError(path, tok.line(),
                       "expected 'facet' or 'endsolid', found " + quote_token_printable(t));
    const std::string where = "in facet " + std::to_string(facet) + " (0-based)";
    expect("normal", where.c_str());
    for (int k = 0; k < 3; ++k) {  // the normal is recomputed downstream; only its syntax matters
      double v;
      const std::string_view n = tok.next();
      if (!parse_whole_token(n, v))
        throw InputError(path, tok.line(), "facet " + std::to_string(facet) + " (0-based): normal component " +
                                               (n.empty() ? std::string("missing") : quote_token_printable(n)) + " is not a number");
    }
    expect("outer", where.c_str());
    expect("loop", where.c_str());
    std::uint32_t ids[3];
    for (int k = 0; k < 3; ++k) {
      expect("vertex", (where + " (corner " + std::to_string(k) + "; exactly 3 per facet)").c_str());
      double c[3];
      for (int j = 0; j < 3; ++j) {
        const std::string_view n = tok.next();
        if (!parse_whole_token(n, c[j]))
          throw InputError(path, tok.line(),
                           "facet " + std::to_string(facet) + " (0-based), corner " +
                               std::to_string(k) + ": coordinate " +
                               (n.empty() ? std::string("missing") : quote_token_printable(n)) + " is not a number");
        if (!std::isfinite(c[j]))
          throw InputError(path, tok.line(),
                           "facet " + std::to_string(facet) + " (0-based), corner " +
                               std::to_string(k) + ": non-finite coordinate " + quote_token_printable(n));
      }
      ids[k] = weld.add(c[0], c[1], c[2]);
    }
    expect("endloop", (where + " (exactly 3 vertices per facet)").c_str());
    expect("endfacet", where.c_str());
    mesh.tris.insert(mesh.tris.end(), ids, ids + 3);
    ++facet;
    if (facet > 0xFFFFFFFFull) throw InputError(path, tok.line(), "more than 2^32-1 facets");
  }
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// PLY
// ---------------------------------------------------------------------------------------------
namespace {
/// The header's 'vertex' and 'face' elements, checked to describe a surface whose declared
/// counts the data section (nbytes) can hold: InputError otherwise, before any allocation.
std::pair<const PlyElement*, const PlyElement*> ply_surface_elements(const std::string& path, const PlyHeader& h,
                                                                     std::size_t nbytes) {
  const PlyElement* vert_el = nullptr;
  const PlyElement* face_el = nullptr;
  for (const PlyElement& e : h.elements) {
    if (e.name == "vertex") vert_el = &e;
    if (e.name == "face") face_el = &e;
  }
  if (!vert_el) throw InputError(path, 0, "PLY file has no 'vertex' element");
  for (int c = 0; c < 3; ++c)
    if (std::none_of(vert_el->props.begin(), vert_el->props.end(),
                     [&](const PlyProperty& p) { return p.role == c; }))
      throw InputError(path, vert_el->line,
                       std::string("'vertex' element has no '") + char('x' + c) + "' property");
  if (!face_el) throw InputError(path, 0, "PLY file has no 'face' element (a point cloud, not a surface)");
  if (std::none_of(face_el->props.begin(), face_el->props.end(),
                   [](const PlyProperty& p) { return p.role == kPlyFaceIndices; }))
    throw InputError(path, face_el->line,
                     "'face' element has no 'vertex_indices' (or 'vertex_index') list property");
  if (vert_el->count > 0xFFFFFFFFull)
    throw InputError(path, vert_el->line, "more than 2^32-1 vertices");

  // Counts the file cannot hold are rejected before anything is allocated from them.
  for (const PlyElement& e : h.elements) {
    if (!ply_count_fits(e, h.format, nbytes))
      throw InputError(path, e.line,
                       "element '" + e.name + "' declares " + std::to_string(e.count) +
                           " records of at least " + std::to_string(ply_min_record_size(e, h.format)) +
                           " bytes, but the data section has only " + std::to_string(nbytes) +
                           " bytes (truncated or corrupt file)");
  }
  return {vert_el, face_el};
}
}  // namespace

SurfaceMesh read_ply_data(const std::string& path, std::string_view data) {
  const PlyHeader h = parse_ply_header(path, data);
  const auto [vert_el, face_el] = ply_surface_elements(path, h, data.size() - h.data_offset);

  SurfaceMesh mesh;
  std::vector<double> raw(3 * vert_el->count);
  mesh.tris.reserve(3 * face_el->count);
  FaceSink sink{path, vert_el->count, mesh.tris, {}, {}, {}};

  if (h.format == PlyFormat::ascii) {
    Tokens tok(data.substr(h.data_offset), h.data_first_line);
    std::uint64_t prev_line = 0;
    std::string prev_name;
    for (const PlyElement& e : h.elements) {
      const bool is_vert = &e == vert_el, is_face = &e == face_el;
      for (std::uint64_t i = 0; i < e.count; ++i) {
        auto eof = [&] {
          return InputError(path, tok.line(),
                            "unexpected end of file in element '" + e.name + "' record " +
                                std::to_string(i) + " (0-based) of " + std::to_string(e.count));
        };
        std::uint64_t line = 0;
        auto where = [] { return std::string(); };
        // One record per line: a record's values all sit on one line, after the previous one's.
        auto value = [&] {
          const std::string_view t = tok.next();
          if (t.empty()) throw eof();
          if (line == 0) {
            if (tok.line() == prev_line)
              throw InputError(path, prev_line,
                               "more values on the line than the properties of element '" +
                                   prev_name + "' declare");
            line = tok.line();
          } else if (tok.line() != line) {
            throw InputError(path, line, "element '" + e.name + "' record " + std::to_string(i) +
                                             " (0-based): too few values on the line");
          }
          return t;
        };
        for (const PlyProperty& p : e.props) {
          std::string_view t = value();
          if (!p.is_list) {
            double v;
            if (!parse_whole_token(t, v))
              throw InputError(path, line, "element '" + e.name + "' record " + std::to_string(i) +
                                               ": property '" + p.name + "' value " + quote_token_printable(t) +
                                               " is not a number");
            if (is_vert && p.role >= 0) {
              if (!std::isfinite(v))
                throw InputError(path, line, "vertex " + std::to_string(i) +
                                                 " (0-based): non-finite coordinate " + p.name + " = " + quote_token_printable(t));
              raw[3 * i + std::size_t(p.role)] = v;
            }
            continue;
          }
          std::uint64_t n;
          if (!parse_whole_token(t, n))
            throw InputError(path, line, "element '" + e.name + "' record " + std::to_string(i) +
                                             ": list length " + quote_token_printable(t) + " is not a non-negative integer");
          if (n > tok.remaining()) throw eof();
          for (std::uint64_t k = 0; k < n; ++k) {
            t = value();
            if (is_face && p.role == kPlyFaceIndices) {
              std::int64_t v;
              if (!parse_whole_token(t, v))
                throw InputError(path, line, "face " + std::to_string(i) + " (0-based): vertex index " +
                                                 quote_token_printable(t) + " is not an integer");
              sink.index(v, i, line, where);
            } else {
              double v;
              if (!parse_whole_token(t, v))
                throw InputError(path, line, "element '" + e.name + "' record " + std::to_string(i) +
                                                 ": list item " + quote_token_printable(t) + " is not a number");
            }
          }
        }
        if (is_face) sink.finish(i, line, where);
        if (line != 0) {
          prev_line = line;
          prev_name = e.name;
        }
      }
    }
    if (!tok.next().empty())
      throw InputError(path, tok.line(), "unexpected data after the last declared element");
  } else {
    const bool swap = ply_needs_swap(h.format);
    const auto* base = reinterpret_cast<const unsigned char*>(data.data());
    const unsigned char* p = base + h.data_offset;
    const unsigned char* end = base + data.size();
    for (const PlyElement& e : h.elements) {
      const bool is_vert = &e == vert_el, is_face = &e == face_el;
      for (std::uint64_t i = 0; i < e.count; ++i) {
        const std::size_t rec_offset = std::size_t(p - base);
        auto where = [&] { return ", byte offset " + std::to_string(rec_offset); };
        auto truncated = [&] {
          return InputError(path, 0,
                            "truncated file: element '" + e.name + "' record " + std::to_string(i) +
                                " (0-based, byte offset " + std::to_string(rec_offset) + ") of " +
                                std::to_string(e.count) + " runs past the end of the file");
        };
        const PlyProperty* fault = nullptr;
        const PlyRecordEnd status = walk_ply_binary_record(
            e, p, end, swap, fault,
            [&](const PlyProperty& prop, const unsigned char* bytes) {
              if (!is_vert || prop.role < 0) return;
              const double v = load_ply_double(bytes, prop.type, swap);
              if (!std::isfinite(v))
                throw InputError(path, 0, "vertex " + std::to_string(i) + " (0-based, byte offset " +
                                              std::to_string(bytes - base) + "): non-finite coordinate " +
                                              prop.name);
              raw[3 * i + std::size_t(prop.role)] = v;
            },
            [&](const PlyProperty& prop, std::size_t n, const unsigned char* items) {
              if (!is_face || prop.role != kPlyFaceIndices) return;
              const std::size_t isize = ply_size(prop.type);
              for (std::size_t k = 0; k < n; ++k) sink.index(load_ply_int(items + k * isize, prop.type, swap), i, 0, where);
            });
        if (status == PlyRecordEnd::truncated) throw truncated();
        if (status == PlyRecordEnd::negative_list_length)
          throw InputError(path, 0, "element '" + e.name + "' record " + std::to_string(i) +
                                        " (0-based" + where() + "): negative list length");
        if (is_face) sink.finish(i, 0, where);
      }
    }
  }
  if (mesh.tris.size() / 3 > 0xFFFFFFFFull) throw InputError(path, 0, "more than 2^32-1 triangles");
  sink.triangulate_polygons(raw);

  weld_file_vertices(raw, mesh);
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// Writers
// ---------------------------------------------------------------------------------------------

void check_writable(const SurfaceMesh& mesh, const char* who) {
  const std::size_t n = mesh.points.size();
  for (std::size_t i = 0; i < mesh.points.xyz.size(); ++i)
    if (!std::isfinite(mesh.points.xyz[i]))
      throw UsageError(std::string(who) + ": point " + std::to_string(i / 3) + " has a non-finite coordinate");
  if (mesh.tris.size() % 3 != 0) throw UsageError(std::string(who) + ": tris.size() is not a multiple of 3");
  for (std::size_t i = 0; i < mesh.tris.size(); ++i)
    if (mesh.tris[i] >= n)
      throw UsageError(std::string(who) + ": facet " + std::to_string(i / 3) + " refers to point " +
                       std::to_string(mesh.tris[i]) + " of " + std::to_string(n));
  if (mesh.num_tris() > 0xFFFFFFFFull) throw UsageError(std::string(who) + ": more than 2^32-1 facets");
}

template <class T>
void put_le(std::string& out, T v) {
  using U = std::conditional_t<sizeof(T) == 1, std::uint8_t,
                               std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>;
  U u = std::bit_cast<U>(v);
  if constexpr (sizeof(T) > 1 && std::endian::native == std::endian::big) u = bswap(u);
  char b[sizeof u];
  std::memcpy(b, &u, sizeof u);
  out.append(b, sizeof u);
}

void put_double(std::string& out, double v) {
  char b[32];
  out.append(b, std::to_chars(b, b + sizeof b, v).ptr);
}

/// Unit normal of facet f in float (zero for a degenerate facet), for STL.
void facet_normal(const SurfaceMesh& m, std::size_t f, float n[3]) {
  const double* a = m.points.p(m.tri(f)[0]);
  const double* b = m.points.p(m.tri(f)[1]);
  const double* c = m.points.p(m.tri(f)[2]);
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  double x = u[1] * v[2] - u[2] * v[1], y = u[2] * v[0] - u[0] * v[2], z = u[0] * v[1] - u[1] * v[0];
  const double len = std::sqrt(x * x + y * y + z * z);
  if (!(len > 0) || !std::isfinite(len)) {
    x = y = z = 0;
  } else {
    x /= len;
    y /= len;
    z /= len;
  }
  n[0] = float(x);
  n[1] = float(y);
  n[2] = float(z);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Public API
// ---------------------------------------------------------------------------------------------

SurfaceMesh read_surface(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".stl") return read_stl(path);
  if (ext == ".ply") return read_ply(path);
  if (ext == ".obj") return read_obj(path);
  if (ext == ".off") return read_off(path);
  if (ext == ".om")  // the measurement is in this file's header comment
    throw InputError(path, 0,
                     "OpenMesh .om files are not read: the format stores OpenMesh's half-edge structure, "
                     "not the file's raw faces, and OpenMesh 9.0's reader trusts its indices; "
                     "export the surface as .obj, .off or .ply");
  std::string supported;
  for (std::string_view e : kSurfaceExtensions) supported += (supported.empty() ? "" : ", ") + std::string(e);
  throw InputError(path, 0, "unknown surface file extension " + quote_token_printable(ext) + " (supported: " + supported + ")");
}

SurfaceMesh read_stl(const std::string& path) {
  const std::string raw = read_surface_file(path);
  // Ascii text: a UTF-8 byte order mark (some Windows editors write one) is not part of it.
  const std::string_view text = std::string_view(raw).substr(raw.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0);
  // The size rule alone decides binary: 84 + 50 * count == file size.
  if (raw.size() >= 84) {
    const std::uint32_t count =
        load_le<std::uint32_t>(reinterpret_cast<const unsigned char*>(raw.data()) + 80);
    const std::uint64_t expect = 84 + 50 * std::uint64_t(count);
    if (expect == raw.size()) return read_stl_binary(path, raw);
    // Not a binary STL by size. An ascii STL starts with "solid" and holds text only.
    std::size_t i = 0;
    while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    const bool solid = text.size() - i >= 5 && iequals(text.substr(i, 5), "solid");
    const bool has_nul = std::memchr(text.data(), '\0', std::min<std::size_t>(text.size(), 4096)) != nullptr;
    if (!solid || has_nul)
      throw InputError(path, 0,
                       "not a valid STL file: as binary STL its header (byte offset 80) declares " +
                           std::to_string(count) + " triangles, which needs " +
                           std::to_string(expect) + " bytes, but the file has " +
                           std::to_string(raw.size()) +
                           " bytes (truncated, or a wrong triangle count); it is not ascii STL either" +
                           (solid ? " (it contains binary NUL bytes)" : " (it does not start with 'solid')"));
  }
  return read_stl_ascii(path, text);
}

SurfaceMesh read_ply(const std::string& path) {
  const std::string data = read_surface_file(path);
  return read_ply_data(path, data);
}

void write_stl(const SurfaceMesh& mesh, const std::string& path, bool binary) {
  check_writable(mesh, "write_stl");
  std::string out;
  if (binary) {
    // Binary STL stores float coordinates: doubles are rounded to the nearest float.
    out.reserve(84 + 50 * mesh.num_tris());
    std::string header = "kdmesh binary STL";  // never "solid...": some readers sniff for it
    header.resize(80, ' ');
    out += header;
    put_le(out, std::uint32_t(mesh.num_tris()));
    for (std::size_t f = 0; f < mesh.num_tris(); ++f) {
      float n[3];
      facet_normal(mesh, f, n);
      for (float v : n) put_le(out, v);
      for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 3; ++j) put_le(out, float(mesh.points.p(mesh.tri(f)[k])[j]));
      out.append(2, '\0');
    }
  } else {
    // Ascii STL with shortest round-trip doubles: reading it back gives the exact coordinates.
    out += "solid kdmesh\n";
    for (std::size_t f = 0; f < mesh.num_tris(); ++f) {
      float n[3];
      facet_normal(mesh, f, n);
      out += "  facet normal ";
      for (int j = 0; j < 3; ++j) {
        put_double(out, n[j]);
        out += j < 2 ? ' ' : '\n';
      }
      out += "    outer loop\n";
      for (int k = 0; k < 3; ++k) {
        out += "      vertex ";
        for (int j = 0; j < 3; ++j) {
          put_double(out, mesh.points.p(mesh.tri(f)[k])[j]);
          out += j < 2 ? ' ' : '\n';
        }
      }
      out += "    endloop\n  endfacet\n";
    }
    out += "endsolid kdmesh\n";
  }
  write_file_atomically(path, out);
}

void write_ply(const SurfaceMesh& mesh, const std::string& path, bool binary) {
  check_writable(mesh, "write_ply");
  const bool big = mesh.points.size() > 0x7FFFFFFFull;
  std::string out = "ply\nformat ";
  out += binary ? "binary_little_endian" : "ascii";
  out += " 1.0\ncomment kdmesh surface\nelement vertex " + std::to_string(mesh.points.size()) +
         "\nproperty double x\nproperty double y\nproperty double z\nelement face " +
         std::to_string(mesh.num_tris()) + "\nproperty list uchar " + (big ? "uint" : "int") +
         " vertex_indices\nend_header\n";
  if (binary) {
    out.reserve(out.size() + 24 * mesh.points.size() + 13 * mesh.num_tris());
    for (double v : mesh.points.xyz) put_le(out, v);
    for (std::size_t f = 0; f < mesh.num_tris(); ++f) {
      out.push_back(char(3));
      for (int k = 0; k < 3; ++k) put_le(out, mesh.tri(f)[k]);
    }
  } else {
    for (std::size_t i = 0; i < mesh.points.size(); ++i) {
      for (int j = 0; j < 3; ++j) {
        put_double(out, mesh.points.p(std::uint32_t(i))[j]);
        out += j < 2 ? ' ' : '\n';
      }
    }
    for (std::size_t f = 0; f < mesh.num_tris(); ++f)
      out += "3 " + std::to_string(mesh.tri(f)[0]) + " " + std::to_string(mesh.tri(f)[1]) + " " +
             std::to_string(mesh.tri(f)[2]) + "\n";
  }
  write_file_atomically(path, out);
}

}  // namespace kdmesh
