// kdmesh — tests of the STL/PLY/OBJ/OFF surface readers and the STL/PLY writers (io/surface_io.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "io/surface_io.h"
#include "tests/support/scratch.h"

namespace kdmesh {
namespace {

using test::scratch_path;

/// Unit cube [0,1]^3 as 12 outward triangles (coordinates exact in float).
SurfaceMesh unit_cube(double s = 1) {
  SurfaceMesh m;
  for (int i = 0; i < 8; ++i) m.points.push_back(s * (i & 1), s * ((i >> 1) & 1), s * ((i >> 2) & 1));
  m.tris = {0, 2, 3, 0, 3, 1,   // z = 0
            4, 5, 7, 4, 7, 6,   // z = 1
            0, 1, 5, 0, 5, 4,   // y = 0
            2, 6, 7, 2, 7, 3,   // y = 1
            0, 4, 6, 0, 6, 2,   // x = 0
            1, 3, 7, 1, 7, 5};  // x = 1
  return m;
}

/// The corner coordinates of every facet, in facet order: a description of a mesh that does
/// not depend on how points are numbered.
std::vector<std::array<double, 9>> facet_coords(const SurfaceMesh& m) {
  std::vector<std::array<double, 9>> out(m.num_tris());
  for (std::size_t f = 0; f < m.num_tris(); ++f)
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j) out[f][3 * k + j] = m.points.p(m.tri(f)[k])[j];
  return out;
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary);
  f.write(bytes.data(), std::streamsize(bytes.size()));
  ASSERT_TRUE(f.good());
}

template <class T>
void put(std::string& s, T v, bool big_endian = false) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (big_endian == (std::endian::native == std::endian::little))
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  s.append(reinterpret_cast<const char*>(b), sizeof(T));
}

/// Runs `f`, expects an InputError, and returns its message.
template <class F>
std::string input_error(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected InputError, got another exception: " << e.what();
    return {};
  }
  ADD_FAILURE() << "expected InputError, nothing was thrown";
  return {};
}

/// `v` in shortest round-trip form: reading it back gives the same double.
std::string exact(double v) {
  char b[32];
  return std::string(b, std::to_chars(b, b + sizeof b, v).ptr);
}

/// `m` as OBJ text (1-based indices). `polygons`: 0 = one 'f' line per facet; otherwise the
/// facets are paired into quads (facets 2i and 2i+1 of unit_cube() share their diagonal).
std::string obj_text(const SurfaceMesh& m, int polygons) {
  std::string s = "# kdmesh test\no cube\n";
  for (std::size_t i = 0; i < m.points.size(); ++i)
    s += "v " + exact(m.points.p(std::uint32_t(i))[0]) + " " + exact(m.points.p(std::uint32_t(i))[1]) + " " +
         exact(m.points.p(std::uint32_t(i))[2]) + "\n";
  for (std::size_t f = 0; f < m.num_tris(); f += polygons ? 2 : 1) {
    const std::uint32_t* t = m.tri(f);
    s += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " + std::to_string(t[2] + 1);
    if (polygons) {  // appended piece by piece: `" " + to_string` trips GCC 12's false -Wrestrict
      s += ' ';
      s += std::to_string(m.tri(f + 1)[2] + 1);
    }
    s += "\n";
  }
  return s;
}

/// `m` as OFF text, one polygon per facet, or per quad as obj_text's.
std::string off_text(const SurfaceMesh& m, int polygons = 0) {
  std::string s = "OFF\n" + std::to_string(m.points.size()) + " " +
                  std::to_string(polygons ? m.num_tris() / 2 : m.num_tris()) + " 0\n";
  for (std::size_t i = 0; i < m.points.size(); ++i)
    s += exact(m.points.p(std::uint32_t(i))[0]) + " " + exact(m.points.p(std::uint32_t(i))[1]) + " " +
         exact(m.points.p(std::uint32_t(i))[2]) + "\n";
  for (std::size_t f = 0; f < m.num_tris(); f += polygons ? 2 : 1) {
    const std::uint32_t* t = m.tri(f);
    s += polygons ? "4 " : "3 ";
    s += std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]);
    if (polygons) {
      s += ' ';
      s += std::to_string(m.tri(f + 1)[2]);
    }
    s += "\n";
  }
  return s;
}

/// `m` as ascii PLY text with quads as obj_text's (write_ply writes triangles only).
std::string quad_ply_text(const SurfaceMesh& m) {
  std::string s = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(m.points.size()) +
                  "\nproperty double x\nproperty double y\nproperty double z\nelement face " +
                  std::to_string(m.num_tris() / 2) + "\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string off = off_text(m, 1);
  return s + off.substr(off.find('\n', off.find('\n') + 1) + 1);  // OFF's body is PLY's
}

/// Reads `text` as a surface file with extension `ext`.
SurfaceMesh read_text(const std::string& text, const char* ext) {
  const std::string path = scratch_path("io_surface", ext);
  write_bytes(path, text);
  return read_surface(path);
}

// ---------------------------------------------------------------------------------------------
// Round trips
// ---------------------------------------------------------------------------------------------

TEST(SurfaceIo, StlBinaryRoundTrip) {
  const SurfaceMesh cube = unit_cube(2.5);  // 2.5 is exact in float
  const std::string path = scratch_path("io_surface", ".stl");
  write_stl(cube, path, /*binary=*/true);
  // Size rule: 84 + 50 * 12 bytes.
  std::ifstream f(path, std::ios::binary | std::ios::ate);
  EXPECT_EQ(std::size_t(f.tellg()), 84u + 50u * 12u);
  const SurfaceMesh back = read_surface(path);
  EXPECT_EQ(back.points.size(), 8u);  // 36 corners welded into the cube's 8 points
  EXPECT_EQ(facet_coords(back), facet_coords(cube));
}

TEST(SurfaceIo, StlAsciiRoundTripIsExactForDoubles) {
  SurfaceMesh cube = unit_cube();
  for (double& v : cube.points.xyz) v = v * 0.1 + 1.0 / 3.0;  // not representable in float
  const std::string path = scratch_path("io_surface", ".STL");  // extension is case-insensitive
  write_stl(cube, path, /*binary=*/false);
  const SurfaceMesh back = read_surface(path);
  EXPECT_EQ(back.points.size(), 8u);
  EXPECT_EQ(facet_coords(back), facet_coords(cube));
}

TEST(SurfaceIo, BinaryStlWhoseHeaderStartsWithSolidReadsAsBinary) {
  // 80-byte header "solid ..." (as some exporters write), 2 facets, 84 + 100 bytes.
  std::string bytes = "solid this is really a binary file";
  bytes.resize(80, ' ');
  put<std::uint32_t>(bytes, 2);
  const float tri[2][9] = {{0, 0, 0, 1, 0, 0, 0, 1, 0}, {1, 0, 0, 1, 1, 0, 0, 1, 0}};
  for (const auto& t : tri) {
    for (int k = 0; k < 3; ++k) put<float>(bytes, 0);  // normal (ignored)
    for (float v : t) put<float>(bytes, v);
    put<std::uint16_t>(bytes, 0);
  }
  ASSERT_EQ(bytes.size(), 184u);
  const std::string path = scratch_path("io_surface", ".stl");
  write_bytes(path, bytes);
  const SurfaceMesh m = read_stl(path);
  ASSERT_EQ(m.num_tris(), 2u);
  EXPECT_EQ(m.points.size(), 4u);  // the shared edge (1,0,0)-(0,1,0) is welded
  // Facet 1 = points (1,0,0), (1,1,0), (0,1,0): first-seen ids 1, 3, 2.
  EXPECT_EQ(std::vector<std::uint32_t>(m.tris.begin(), m.tris.end()),
            (std::vector<std::uint32_t>{0, 1, 2, 1, 3, 2}));
  EXPECT_EQ(m.points.p(3)[0], 1.0);
  EXPECT_EQ(m.points.p(3)[1], 1.0);
}

TEST(SurfaceIo, PlyAsciiAndBinaryLittleEndianRoundTrip) {
  SurfaceMesh cube = unit_cube();
  for (double& v : cube.points.xyz) v = v * 0.7 - 1.0 / 7.0;  // doubles survive both formats
  for (bool binary : {false, true}) {
    const std::string path = scratch_path("io_surface", ".ply");
    write_ply(cube, path, binary);
    const SurfaceMesh back = read_surface(path);
    EXPECT_EQ(back.points.xyz, cube.points.xyz) << (binary ? "binary" : "ascii");
    EXPECT_EQ(back.tris, cube.tris) << (binary ? "binary" : "ascii");
  }
}

/// A binary PLY with float coordinates, an extra uchar vertex property, an extra face
/// property, and an extra element, in either byte order, built byte by byte.
std::string binary_ply(bool big) {
  std::string s = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\ncomment made by hand\nelement vertex 4\nproperty float x\n"
                  "property uchar red\nproperty float y\nproperty double z\n"
                  "element face 2\nproperty list uchar int vertex_indices\nproperty short tag\n"
                  "element edge 1\nproperty int a\nproperty int b\nend_header\n";
  const float xy[4][2] = {{0, 0}, {1.5f, 0}, {0, 2}, {1.5f, 2}};
  for (int i = 0; i < 4; ++i) {
    put<float>(s, xy[i][0], big);
    put<std::uint8_t>(s, 200, big);
    put<float>(s, xy[i][1], big);
    put<double>(s, -0.25 * i, big);
  }
  const std::int32_t faces[2][3] = {{0, 1, 2}, {1, 3, 2}};
  for (const auto& f : faces) {
    put<std::uint8_t>(s, 3, big);
    for (std::int32_t v : f) put<std::int32_t>(s, v, big);
    put<std::int16_t>(s, -7, big);
  }
  put<std::int32_t>(s, 0, big);
  put<std::int32_t>(s, 1, big);
  return s;
}

TEST(SurfaceIo, PlyBinaryBothEndiannessesWithExtraProperties) {
  for (bool big : {false, true}) {
    const std::string path = scratch_path("io_surface", ".ply");
    write_bytes(path, binary_ply(big));
    const SurfaceMesh m = read_ply(path);
    // Expected from the construction above: point i = (xy[i], -0.25 i), no duplicates.
    ASSERT_EQ(m.points.size(), 4u) << big;
    EXPECT_EQ(m.points.xyz, (std::vector<double>{0, 0, 0, 1.5, 0, -0.25, 0, 2, -0.5, 1.5, 2, -0.75}))
        << big;
    EXPECT_EQ(m.tris, (std::vector<std::uint32_t>{0, 1, 2, 1, 3, 2})) << big;
  }
}

TEST(SurfaceIo, PlyAsciiQuadIsFanTriangulated) {
  const std::string path = scratch_path("io_surface", ".ply");
  write_bytes(path,
              "ply\r\nformat ascii 1.0\r\ncomment a square and a triangle\r\n"
              "element vertex 5\r\nproperty double x\r\nproperty double y\r\nproperty double z\r\n"
              "property float confidence\r\nelement face 2\r\n"
              "property list uchar uint vertex_index\r\nend_header\r\n"
              "0 0 0 1\r\n1 0 0 1\r\n1 1 0 1\r\n0 1 0 1\r\n0.5 0.5 1 0.5\r\n"
              "4 0 1 2 3\r\n3 0 1 4\r\n");
  const SurfaceMesh m = read_ply(path);
  // Quad 0 1 2 3 -> (0,1,2), (0,2,3); then the triangle (0,1,4).
  EXPECT_EQ(m.tris, (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 0, 1, 4}));
  EXPECT_EQ(m.points.size(), 5u);
  EXPECT_EQ(m.points.p(4)[0], 0.5);
  EXPECT_EQ(m.points.p(4)[2], 1.0);
}

TEST(SurfaceIo, WeldsBitIdenticalCoordinatesAndSignedZero) {
  // Two facets share the edge (1,0,0)-(0,1,0); one writes a zero as -0. The third point
  // (1e-300, 0, 0) differs from (0,0,0) by one tiny bit pattern and must stay separate.
  const std::string path = scratch_path("io_surface", ".ply");
  write_bytes(path,
              "ply\nformat ascii 1.0\nelement vertex 7\nproperty float64 x\nproperty float64 y\n"
              "property float64 z\nelement face 3\nproperty list uchar int vertex_indices\n"
              "end_header\n0 0 0\n1 0 0\n0 1 0\n1 -0 0\n-0.0 1 0\n1 1 0\n1e-300 0 0\n"
              "3 0 1 2\n3 3 5 4\n3 6 1 2\n");
  const SurfaceMesh m = read_ply(path);
  // Distinct coordinates: (0,0,0) (1,0,0) (0,1,0) (1,1,0) (1e-300,0,0) = 5 points.
  EXPECT_EQ(m.points.size(), 5u);
  EXPECT_EQ(m.tris, (std::vector<std::uint32_t>{0, 1, 2, 1, 3, 2, 4, 1, 2}));
  // The welded point keeps a +0.0 (no -0.0 leaks out).
  EXPECT_FALSE(std::signbit(m.points.p(2)[0]));
}

// The same surface read from OBJ and OFF as from PLY: the same points (bit for bit, in the
// same order) and the same facets. Coordinates 0.1 x are not floats: a reader that goes
// through float (as OpenMesh 9's OBJ and OFF readers do) gives other points.
TEST(SurfaceIoObjOff, CubeAsObjAndOffEqualsCubeAsPly) {
  const SurfaceMesh cube = unit_cube(0.1);
  const std::string ply = scratch_path("io_surface", ".ply");
  write_ply(cube, ply, false);
  const SurfaceMesh from_ply = read_surface(ply);
  const std::pair<const char*, std::string> files[] = {
      {".obj", obj_text(cube, 0)}, {".OBJ", obj_text(cube, 0)}, {".off", off_text(cube)}, {".Off", off_text(cube)}};
  for (const auto& [ext, text] : files) {
    const SurfaceMesh m = read_text(text, ext);
    EXPECT_EQ(m.points.xyz, from_ply.points.xyz) << ext;
    EXPECT_EQ(m.tris, from_ply.tris) << ext;
    EXPECT_EQ(m.points.p(1)[0], 0.1) << ext;
  }
}

// Quads are triangulated as PLY's are: a convex polygon gives its fan from its first vertex.
TEST(SurfaceIoObjOff, QuadsAreFanTriangulatedAsInPly) {
  const SurfaceMesh cube = unit_cube(0.1);
  const SurfaceMesh from_ply = read_text(quad_ply_text(cube), ".ply");
  const SurfaceMesh from_obj = read_text(obj_text(cube, 1), ".obj");
  const SurfaceMesh from_off = read_text(off_text(cube, 1), ".off");
  // The quad (a b c d) written for facets (a b c), (a c d) comes back as those two facets.
  EXPECT_EQ(from_obj.tris, cube.tris);
  EXPECT_EQ(from_off.tris, cube.tris);
  EXPECT_EQ(from_ply.tris, cube.tris);
  EXPECT_EQ(from_obj.points.xyz, from_ply.points.xyz);
  EXPECT_EQ(from_off.points.xyz, from_ply.points.xyz);
  // A pentagon (0,0) (2,0) (2,1) (1,2) (0,1): fan (0 1 2) (0 2 3) (0 3 4).
  const SurfaceMesh penta = read_text("v 0 0 0\nv 2 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\nf 1 2 3 4 5\n", ".obj");
  EXPECT_EQ(penta.tris, (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 0, 3, 4}));
}

// OBJ references v/vt/vn, v//vn and v/vt; negative indices count back from the last vertex
// defined before the line; statements without facets (vt, vn, g, o, s, usemtl, mtllib, l) and
// comments are skipped; CRLF line ends. The same tetrahedron as plain "f a b c" lines.
TEST(SurfaceIoObjOff, ObjReferenceSyntaxNegativeIndicesCommentsAndCrlf) {
  const std::string plain = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  const std::string fancy =
      "# a tetrahedron\r\nmtllib t.mtl\r\no tet\r\nv 0 0 0 # origin\r\nv 1 0 0\r\nv 0 1 0\r\n"
      "vt 0 0\r\nvt 1 0\r\nvn 0 0 -1\r\ng bottom\r\nusemtl red\r\ns off\r\n"
      "f -3/1/1 -1/2/1 -2/1/1\r\n"  // vertices 1 3 2 (the three defined so far)
      "v 0 0 1 1.0\r\nl 1 4\r\n"   // a w coordinate; a polyline (no facet)
      "f 1//1 2//1 -1//1\r\n"        // 1 2 4
      "f 1/1 4/2 3/1\r\n"
      "\r\n\tf\t2  3 4 \r\n";
  const SurfaceMesh a = read_text(plain, ".obj");
  const SurfaceMesh b = read_text(fancy, ".obj");
  EXPECT_EQ(b.tris, (std::vector<std::uint32_t>{0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3}));
  EXPECT_EQ(b.tris, a.tris);
  EXPECT_EQ(b.points.xyz, a.points.xyz);
  // A positive index may name a vertex defined later (as OpenMesh allows); a negative one not.
  const SurfaceMesh later = read_text("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", ".obj");
  EXPECT_EQ(later.tris, (std::vector<std::uint32_t>{0, 1, 2}));
}

// Degenerate and repeated faces reach the caller as the file has them (OpenMesh 9's OBJ
// reader drops "f 1 2 2"); prepare_surface decides what they mean.
TEST(SurfaceIoObjOff, DegenerateFacesAreKeptRaw) {
  const SurfaceMesh obj = read_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2\nf 1 2 3\nf 1 2 3\n", ".obj");
  EXPECT_EQ(obj.tris, (std::vector<std::uint32_t>{0, 1, 1, 0, 1, 2, 0, 1, 2}));
  const SurfaceMesh off = read_text("OFF\n3 3 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 1\n3 0 1 2\n3 0 1 2\n", ".off");
  EXPECT_EQ(off.tris, obj.tris);
}

// OFF variants: counts on the keyword's line (also run together with it, as in ModelNet's
// files), COFF/NOFF extra vertex values, face colours, comments and blank lines (a comment
// before the counts broke OpenMesh 9's reader), CRLF, a byte order mark, "off" in lower case.
TEST(SurfaceIoObjOff, OffVariants) {
  const SurfaceMesh plain = read_text("OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                                      "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n", ".off");
  ASSERT_EQ(plain.num_tris(), 4u);
  const std::string variants[] = {
      "OFF 4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
      "OFF4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",  // as ModelNet's
      "# made by hand\r\nOFF\r\n# counts next\r\n\r\n4 4 6\r\n0 0 0\r\n1 0 0\r\n0 1 0\r\n0 0 1\r\n"
      "3 0 2 1\r\n3 0 1 3\r\n3 0 3 2\r\n3 1 2 3\r\n",
      "COFF\n4 4 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n0 0 1 9 9 9 9\n"
      "3 0 2 1 1 0 0\n3 0 1 3 0 1 0\n3 0 3 2\n3 1 2 3 0.5 0.5 0.5 1\n",
      "NOFF\n4 4 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n0 0 1 0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
      "\xEF\xBB\xBF" "off\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3",
  };
  for (const std::string& text : variants) {
    const SurfaceMesh m = read_text(text, ".off");
    EXPECT_EQ(m.tris, plain.tris) << text;
    EXPECT_EQ(m.points.xyz, plain.points.xyz) << text;
  }
}

// ---------------------------------------------------------------------------------------------
// Hostile input
// ---------------------------------------------------------------------------------------------

TEST(SurfaceIoHostile, TruncatedBinaryStl) {
  const std::string full = scratch_path("io_surface", ".stl");
  write_stl(unit_cube(), full, true);
  std::ifstream in(full, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  bytes.resize(bytes.size() - 30);  // 684 - 30 = 654 bytes
  const std::string path = scratch_path("io_surface", ".stl");
  write_bytes(path, bytes);
  const std::string msg = input_error([&] { read_stl(path); });
  EXPECT_NE(msg.find(path), std::string::npos) << msg;
  EXPECT_NE(msg.find("12 triangles"), std::string::npos) << msg;
  EXPECT_NE(msg.find("684 bytes"), std::string::npos) << msg;
  EXPECT_NE(msg.find("654 bytes"), std::string::npos) << msg;
}

TEST(SurfaceIoHostile, LyingTriangleCountFailsFastWithoutAllocating) {
  std::string bytes(80, '\0');
  put<std::uint32_t>(bytes, 0xFFFFFFFFu);  // 4,294,967,295 triangles claimed
  bytes.append(50, '\0');
  const std::string path = scratch_path("io_surface", ".stl");
  write_bytes(path, bytes);
  const auto t0 = std::chrono::steady_clock::now();
  const std::string msg = input_error([&] { read_stl(path); });
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(s, 1.0);
  EXPECT_NE(msg.find("4294967295 triangles"), std::string::npos) << msg;
  EXPECT_NE(msg.find("134 bytes"), std::string::npos) << msg;
}

TEST(SurfaceIoHostile, LyingPlyCountsFailFast) {
  for (const char* format : {"ascii", "binary_little_endian"}) {
    const std::string path = scratch_path("io_surface", ".ply");
    write_bytes(path, std::string("ply\nformat ") + format +
                          " 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\n"
                          "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                          "end_header\n0 0 0\n");
    const std::string msg = input_error([&] { read_ply(path); });
    EXPECT_NE(msg.find("4000000000"), std::string::npos) << msg;
    EXPECT_NE(msg.find(path + ":3:"), std::string::npos) << msg;  // the 'element vertex' line
  }
}

TEST(SurfaceIoHostile, GarbageAndEmptyFilesAndUnknownExtension) {
  std::string garbage;
  std::uint32_t x = 12345;
  for (int i = 0; i < 1000; ++i) {
    x = x * 1664525u + 1013904223u;
    garbage.push_back(char(x >> 24));
  }
  const std::string stl = scratch_path("io_surface", ".stl");
  write_bytes(stl, garbage);
  EXPECT_NE(input_error([&] { read_surface(stl); }).find("not a valid STL file"), std::string::npos);
  const std::string ply = scratch_path("io_surface", ".ply");
  write_bytes(ply, garbage);
  EXPECT_NE(input_error([&] { read_surface(ply); }).find("not a PLY file"), std::string::npos);

  const std::string small = scratch_path("io_surface", ".stl");  // < 84 bytes, not ascii
  write_bytes(small, "hello world");
  EXPECT_NE(input_error([&] { read_surface(small); }).find(small + ":1:"), std::string::npos);

  const std::string empty = scratch_path("io_surface", ".stl");
  write_bytes(empty, "");
  EXPECT_NE(input_error([&] { read_surface(empty); }).find("empty file"), std::string::npos);

  const std::string dae = scratch_path("io_surface", ".dae");
  write_bytes(dae, "v 0 0 0\n");
  const std::string unknown = input_error([&] { read_surface(dae); });
  EXPECT_NE(unknown.find("unknown surface file extension"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find(".stl, .ply, .obj, .off"), std::string::npos) << unknown;
  // OpenMesh's own format is refused with the reason (surface_io.cpp's measurement), not read.
  const std::string om = scratch_path("io_surface", ".OM");
  write_bytes(om, "OMTB");
  const std::string om_msg = input_error([&] { read_surface(om); });
  EXPECT_NE(om_msg.find(om + ": OpenMesh .om files are not read"), std::string::npos) << om_msg;

  EXPECT_NE(input_error([&] { read_surface(scratch_path("io_surface", ".stl")); }).find("cannot open"),
            std::string::npos);
}

TEST(SurfaceIoHostile, PlyIndexOutOfRange) {
  const std::string path = scratch_path("io_surface", ".ply");
  write_bytes(path,
              "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
              "property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
              "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 3 2\n");
  const std::string msg = input_error([&] { read_ply(path); });
  // Line 14 is "3 0 3 2": face 1 uses vertex 3 of 3.
  EXPECT_NE(msg.find(path + ":14:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("face 1"), std::string::npos) << msg;
  EXPECT_NE(msg.find("vertex index 3 is out of range"), std::string::npos) << msg;

  // Same in binary: a negative index; the message names the record's byte offset.
  std::string b = "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\n"
                  "property float y\nproperty float z\nelement face 1\n"
                  "property list uchar int vertex_indices\nend_header\n";
  const std::size_t face_offset = b.size() + 3 * 12;
  for (int i = 0; i < 9; ++i) put<float>(b, float(i == 3 || i == 7), true);
  put<std::uint8_t>(b, 3, true);
  put<std::int32_t>(b, 0, true);
  put<std::int32_t>(b, -1, true);
  put<std::int32_t>(b, 2, true);
  const std::string bin = scratch_path("io_surface", ".ply");
  write_bytes(bin, b);
  const std::string bmsg = input_error([&] { read_ply(bin); });
  EXPECT_NE(bmsg.find("face 0"), std::string::npos) << bmsg;
  EXPECT_NE(bmsg.find("byte offset " + std::to_string(face_offset)), std::string::npos) << bmsg;
  EXPECT_NE(bmsg.find("vertex index -1"), std::string::npos) << bmsg;
}

TEST(SurfaceIoHostile, NonFiniteCoordinates) {
  // ascii STL: NaN in facet 1, corner 2, on line 13 (7 lines per facet after "solid").
  SurfaceMesh two = unit_cube();
  two.tris.resize(6);
  const std::string stl = scratch_path("io_surface", ".stl");
  write_stl(two, stl, false);
  std::ifstream in(stl);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Lines: 1 solid, 2-8 facet 0, 9 facet normal, 10 outer loop, 11-13 vertices of facet 1.
  std::size_t pos = 0;
  for (int line = 1; line < 13; ++line) pos = text.find('\n', pos) + 1;
  const std::size_t vtx = text.find("vertex ", pos);
  ASSERT_EQ(vtx, text.find_first_not_of(' ', pos));
  text.replace(vtx + 7, text.find(' ', vtx + 7) - (vtx + 7), "nan");
  const std::string bad_stl = scratch_path("io_surface", ".stl");
  write_bytes(bad_stl, text);
  const std::string msg = input_error([&] { read_stl(bad_stl); });
  EXPECT_NE(msg.find(bad_stl + ":13:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("facet 1"), std::string::npos) << msg;
  EXPECT_NE(msg.find("corner 2"), std::string::npos) << msg;
  EXPECT_NE(msg.find("non-finite"), std::string::npos) << msg;

  // binary STL: +inf in facet 1.
  std::string b(80, ' ');
  put<std::uint32_t>(b, 2);
  for (int f = 0; f < 2; ++f) {
    for (int k = 0; k < 12; ++k)
      put<float>(b, f == 1 && k == 7 ? std::numeric_limits<float>::infinity() : float(k % 3));
    put<std::uint16_t>(b, 0);
  }
  const std::string bin = scratch_path("io_surface", ".stl");
  write_bytes(bin, b);
  const std::string bmsg = input_error([&] { read_stl(bin); });
  EXPECT_NE(bmsg.find("facet 1"), std::string::npos) << bmsg;
  EXPECT_NE(bmsg.find("non-finite"), std::string::npos) << bmsg;

  // binary PLY: NaN as vertex 2's y.
  std::string p = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\n"
                  "property double y\nproperty double z\nelement face 1\n"
                  "property list uchar int vertex_indices\nend_header\n";
  for (int i = 0; i < 9; ++i) put<double>(p, i == 7 ? std::nan("") : double(i));
  put<std::uint8_t>(p, 3);
  for (int i = 0; i < 3; ++i) put<std::int32_t>(p, i);
  const std::string ply = scratch_path("io_surface", ".ply");
  write_bytes(ply, p);
  const std::string pmsg = input_error([&] { read_ply(ply); });
  EXPECT_NE(pmsg.find("vertex 2"), std::string::npos) << pmsg;
  EXPECT_NE(pmsg.find("non-finite coordinate y"), std::string::npos) << pmsg;
}

TEST(SurfaceIoHostile, TruncatedPlyAndMalformedAsciiStl) {
  std::string p = binary_ply(false);
  p.resize(p.size() - 5);  // cuts into the 'edge' element
  const std::string ply = scratch_path("io_surface", ".ply");
  write_bytes(ply, p);
  const std::string msg = input_error([&] { read_ply(ply); });
  EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;

  // ascii PLY is one record per line: an extra value on line 11 (vertex 1) is named there,
  // and a face line missing a value is named too.
  const std::string extra = scratch_path("io_surface", ".ply");
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  write_bytes(extra, head + "0 0 0\n1 0 0 7\n0 1 0\n3 0 1 2\n");
  const std::string emsg = input_error([&] { read_ply(extra); });
  EXPECT_NE(emsg.find(extra + ":11:"), std::string::npos) << emsg;
  EXPECT_NE(emsg.find("more values"), std::string::npos) << emsg;
  const std::string few = scratch_path("io_surface", ".ply");
  write_bytes(few, head + "0 0 0\n1 0 0\n0 1 0\n3 0 1\n");
  const std::string fmsg = input_error([&] { read_ply(few); });
  EXPECT_NE(fmsg.find("end of file"), std::string::npos) << fmsg;
  write_bytes(few, head + "0 0 0\n1 0\n0 1 0\n3 0 1 2\n");
  const std::string gmsg = input_error([&] { read_ply(few); });
  EXPECT_NE(gmsg.find(few + ":11:"), std::string::npos) << gmsg;
  EXPECT_NE(gmsg.find("too few values"), std::string::npos) << gmsg;

  const std::string stl = scratch_path("io_surface", ".stl");
  write_bytes(stl, "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                   "vertex 0 1 0\nvertex 1 1 0\nendloop\nendfacet\nendsolid x\n");
  const std::string smsg = input_error([&] { read_stl(stl); });
  EXPECT_NE(smsg.find(stl + ":7:"), std::string::npos) << smsg;  // the 4th vertex
  EXPECT_NE(smsg.find("expected 'endloop'"), std::string::npos) << smsg;

  const std::string open = scratch_path("io_surface", ".stl");
  write_bytes(open, "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n");
  EXPECT_NE(input_error([&] { read_stl(open); }).find("end of file"), std::string::npos);
}

// An OFF header count the file cannot hold is refused from the header line, before anything
// is allocated from it (OpenMesh 9 reserved 4e9 faces and ran out of memory on this file).
TEST(SurfaceIoHostile, LyingOffCountsFailFastWithoutAllocating) {
  const std::string body = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  for (const char* counts : {"4 4000000000 0", "400000000 4 0", "18446744073709551615 4 0", "4 40 0"}) {
    const std::string path = scratch_path("io_surface", ".off");
    write_bytes(path, "OFF\n" + std::string(counts) + "\n" + body);
    const auto t0 = std::chrono::steady_clock::now();
    const std::string msg = input_error([&] { read_off(path); });
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0);
    EXPECT_NE(msg.find(path + ":2: the header declares"), std::string::npos) << msg;
    EXPECT_NE(msg.find("only " + std::to_string(body.size()) + " bytes follow"), std::string::npos) << msg;
  }
  // A count that the bytes could hold but the lines do not: the missing record, by line.
  const std::string path = scratch_path("io_surface", ".off");
  write_bytes(path, "OFF\n4 5 0\n" + body + "                                  \n");
  std::string msg = input_error([&] { read_off(path); });
  EXPECT_NE(msg.find(path + ":11: unexpected end of file: face 4 (0-based) of the 5"), std::string::npos) << msg;
  // Fewer faces declared than the file holds: the extra line is named, not dropped.
  write_bytes(path, "OFF\n4 3 0\n" + body);
  msg = input_error([&] { read_off(path); });
  EXPECT_NE(msg.find(path + ":10: unexpected data after the last of the 3 faces"), std::string::npos) << msg;
}

TEST(SurfaceIoHostile, ObjAndOffIndexOutOfRangeNamesTheLine) {
  const std::string obj = scratch_path("io_surface", ".obj");
  const std::string verts = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n";
  const struct {
    std::string faces, want;
  } obj_cases[] = {
      {"f 1 3 2\nf 1 2 9\n", ":6: face 1 (0-based): vertex index 9 is out of range (the file has 4 vertices"},
      {"f 1 3 2\n\nf 0 1 2\n", ":7: face 1 (0-based): vertex index 0 is out of range"},
      {"f -5 -1 -2\n", ":5: face 0 (0-based): relative vertex index -5 is out of range (only 4 vertices"},
      {"f 1 2 x\n", ":5: face 0 (0-based): vertex reference 'x' is not an index"},
      {"f 1/1 2/2 /3\n", ":5: face 0 (0-based): vertex reference '/3' is not an index"},
      {"f 1 2\n", ":5: face 0 (0-based) has 2 vertices; at least 3 are needed"},
      {"v 1 2\nf 1 2 3\n", ":5: vertex 5 (1-based): coordinate z is missing"},
      {"v 1 nan 2\nf 1 2 3\n", ":5: vertex 5 (1-based): non-finite coordinate y"},
      {"vt 0 0\n", ": no faces ('f' lines): a point cloud"},
  };
  for (const auto& c : obj_cases) {
    write_bytes(obj, verts + c.faces);
    const std::string msg = input_error([&] { read_surface(obj); });
    EXPECT_NE(msg.find(obj + c.want), std::string::npos) << msg;
  }
  const std::string off = scratch_path("io_surface", ".off");
  const struct {
    std::string text, want;
  } off_cases[] = {
      {"OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 3 2\n", ":7: face 1 (0-based): vertex index 3 is out of range (3 vertices)"},
      {"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", ":6: face 0 (0-based): vertex index -1 is out of range"},
      {"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", ":6: face 0 (0-based) declares 4 vertices, but the line holds 3"},
      {"OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2 # long enough for the counts\n", ":4: vertex 1 (0-based): coordinate z is missing"},
      {"OFF BINARY\n3 1 0\n", ":1: binary OFF is not supported"},
      {"4OFF\n3 1 0\n", ":1: '4OFF': 4OFF and nOFF"},
      {"PLY\n3 1 0\n", ":1: not an OFF file"},
      {"OFF\n3 x 0\n", ":2: OFF header: the face count 'x' is not a non-negative integer"},
      {"OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", ":2: no faces: a point cloud"},
  };
  for (const auto& c : off_cases) {
    write_bytes(off, c.text);
    const std::string msg = input_error([&] { read_surface(off); });
    EXPECT_NE(msg.find(off + c.want), std::string::npos) << msg;
  }
}

TEST(SurfaceIoHostile, MutatedFilesGiveInputErrorOrAMeshNeverACrash) {
  // Valid files in every format, then random byte changes and truncations: each read must
  // either succeed with in-range facet ids or throw InputError (nothing else, no crash; the
  // sanitizer build checks memory safety).
  SurfaceMesh cube = unit_cube();
  std::vector<std::string> originals;
  std::vector<const char*> extensions = {".stl", ".stl", ".ply", ".ply", ".ply", ".obj", ".off"};
  for (int fmt = 0; fmt < 4; ++fmt) {
    const std::string path = scratch_path("io_surface", extensions[std::size_t(fmt)]);
    if (fmt < 2)
      write_stl(cube, path, fmt == 0);
    else
      write_ply(cube, path, fmt == 2);
    std::ifstream in(path, std::ios::binary);
    originals.emplace_back((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }
  originals.push_back(binary_ply(true));
  originals.push_back(obj_text(cube, 0) + "vt 0 0\nvn 0 0 1\nf -1/1/1 -2//1 -3\n");
  originals.push_back(off_text(cube));
  std::uint64_t x = 88172645463325252ull;  // xorshift64
  auto rnd = [&] {
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    return x;
  };
  int ok = 0, errors = 0;
  for (std::size_t fmt = 0; fmt < originals.size(); ++fmt) {
    const std::string path = scratch_path("io_surface", extensions[fmt]);  // reused
    for (int trial = 0; trial < 150; ++trial) {
      std::string bytes = originals[fmt];
      const int edits = 1 + int(rnd() % 4);
      for (int e = 0; e < edits; ++e) {
        const std::size_t at = rnd() % bytes.size();
        switch (rnd() % 4) {
          case 0: bytes[at] = char(rnd()); break;
          case 1: bytes.resize(at + 1); break;
          case 2: bytes[at] = "0123456789 -.\n"[rnd() % 15]; break;
          default: bytes.insert(at, 1, char(rnd())); break;
        }
      }
      write_bytes(path, bytes);
      try {
        const SurfaceMesh m = read_surface(path);
        for (std::uint32_t v : m.tris) ASSERT_LT(v, m.points.size());
        ASSERT_EQ(m.tris.size() % 3, 0u);
        ++ok;
      } catch (const InputError&) {
        ++errors;
      }
    }
  }
  EXPECT_GT(errors, 0);  // the mutations do break files
  EXPECT_EQ(ok + errors, int(7 * 150));
}

TEST(SurfaceIo, WritersAreAtomicAndReportFailures) {
  // A directory that does not exist: OutputError, nothing written.
  const std::string dir = scratch_path("io_surface", "");
  EXPECT_THROW(write_stl(unit_cube(), dir + "/missing/x.stl"), OutputError);
  EXPECT_THROW(write_ply(unit_cube(), dir + "/missing/x.ply"), OutputError);
  SurfaceMesh bad = unit_cube();
  bad.tris[5] = 8;  // refers to a point that does not exist
  EXPECT_THROW(write_ply(bad, scratch_path("io_surface", ".ply")), UsageError);
}

}  // namespace
}  // namespace kdmesh
