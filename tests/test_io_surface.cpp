// kdmesh — tests of the STL/PLY surface readers and writers (io/surface_io.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
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

  const std::string obj = scratch_path("io_surface", ".obj");
  write_bytes(obj, "v 0 0 0\n");
  EXPECT_NE(input_error([&] { read_surface(obj); }).find("unknown surface file extension"),
            std::string::npos);

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

TEST(SurfaceIoHostile, MutatedFilesGiveInputErrorOrAMeshNeverACrash) {
  // Valid files in every format, then random byte changes and truncations: each read must
  // either succeed with in-range facet ids or throw InputError (nothing else, no crash; the
  // sanitizer build checks memory safety).
  SurfaceMesh cube = unit_cube();
  std::vector<std::string> originals;
  for (int fmt = 0; fmt < 4; ++fmt) {
    const std::string path = scratch_path("io_surface", fmt < 2 ? ".stl" : ".ply");
    if (fmt < 2)
      write_stl(cube, path, fmt == 0);
    else
      write_ply(cube, path, fmt == 2);
    std::ifstream in(path, std::ios::binary);
    originals.emplace_back((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }
  originals.push_back(binary_ply(true));
  std::uint64_t x = 88172645463325252ull;  // xorshift64
  auto rnd = [&] {
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    return x;
  };
  int ok = 0, errors = 0;
  for (std::size_t fmt = 0; fmt < originals.size(); ++fmt) {
    const std::string path = scratch_path("io_surface", fmt < 2 ? ".stl" : ".ply");  // reused
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
  EXPECT_EQ(ok + errors, int(5 * 150));
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
