// SPDX-License-Identifier: AGPL-3.0-or-later
// Point-set readers and the .xyz writer: round trips, tolerated syntax, and precise errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "core/error.h"
#include "tests/support/scratch.h"
#include "io/points_io.h"

namespace kdmesh {
namespace {

namespace fs = std::filesystem;

std::string scratch(const std::string& ext) { return test::scratch_path("io_points", ext); }

std::string write_file(const std::string& ext, const std::string& bytes) {
  const std::string path = scratch(ext);
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

std::uint64_t bits(double d) { return std::bit_cast<std::uint64_t>(d); }

/// Runs `f`, expecting an InputError that names `path`'s file and `line` (0: no line), and
/// whose message contains `needle`.
void expect_input_error(const std::function<void()>& f, const std::string& path, std::uint64_t line,
                        const std::string& needle) {
  try {
    f();
    ADD_FAILURE() << "no InputError thrown; expected one containing '" << needle << "'";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.file(), path) << what;
    EXPECT_EQ(e.line(), line) << what;
    EXPECT_NE(what.find(fs::path(path).filename().string()), std::string::npos) << what;
    if (line) {
      EXPECT_NE(what.find(":" + std::to_string(line) + ":"), std::string::npos) << what;
    }
    EXPECT_NE(what.find(needle), std::string::npos) << "'" << needle << "' not in: " << what;
    EXPECT_EQ(e.code(), ExitCode::input);
  }
}

/// read_xyz on `content` must fail at `line` with `needle` in the message.
void expect_xyz_error(const std::string& content, std::uint64_t line, const std::string& needle) {
  const std::string path = write_file(".xyz", content);
  expect_input_error([&] { read_xyz(path); }, path, line, needle);
}

void expect_points(const PointSet& got, const std::vector<double>& want) {
  ASSERT_EQ(got.xyz.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i)
    EXPECT_EQ(bits(got.xyz[i]), bits(want[i]))
        << "coordinate " << i << ": " << got.xyz[i] << " vs " << want[i];
}

// ---------------------------------------------------------------------------------------------
// .xyz
// ---------------------------------------------------------------------------------------------

TEST(Xyz, RoundTripIsBitExactOnAwkwardDoubles) {
  constexpr double kDenormMin = std::numeric_limits<double>::denorm_min();
  constexpr double kMinNormal = std::numeric_limits<double>::min();
  PointSet p;
  p.push_back(1e-300, 1.0 / 3.0, -0.0);
  p.push_back(1e300, 0.1 + 0.2, kDenormMin);
  p.push_back(-kDenormMin, kMinNormal, std::nextafter(kMinNormal, 0.0));  // largest denormal
  p.push_back(std::numeric_limits<double>::max(), std::numeric_limits<double>::lowest(), 0.0);
  p.push_back(9007199254740993.0, -2.0 / 3.0, 123456.789e-20);
  // Plus random finite bit patterns, which cover every exponent.
  std::mt19937_64 rng(12345);
  while (p.size() < 20000) {
    double c[3];
    for (double& x : c) {
      do x = std::bit_cast<double>(rng());
      while (!std::isfinite(x));
    }
    p.push_back(c[0], c[1], c[2]);
  }
  const std::string path = scratch(".xyz");
  write_xyz(p, path);
  expect_points(read_xyz(path), p.xyz);

  std::ifstream in(path);
  std::string first;
  std::getline(in, first);
  EXPECT_EQ(first, "# kdmesh points: " + std::to_string(p.size()));
}

TEST(Xyz, EmptySetRoundTrips) {
  const std::string path = scratch(".xyz");
  write_xyz(PointSet{}, path);
  EXPECT_TRUE(read_xyz(path).empty());
  EXPECT_TRUE(read_xyz(write_file(".xyz", "")).empty());
  EXPECT_TRUE(read_xyz(write_file(".xyz", "# only a comment\n\n  \t\n")).empty());
}

TEST(Xyz, ToleratesCommentsBlankLinesCrlfTabsAndSigns) {
  const std::string path = write_file(".xyz",
                                      "# header comment\r\n"
                                      "\n"
                                      "1 2 3\r\n"
                                      "\t4\t5   6 # trailing comment\n"
                                      "   \t \r\n"
                                      "+7e0 -8.5 .25\n"
                                      "1e-3 2E2 -0"  // no final newline
  );
  expect_points(read_xyz(path), {1, 2, 3, 4, 5, 6, 7, -8.5, 0.25, 1e-3, 2e2, -0.0});
}

TEST(Xyz, WrongFieldCountNamesLine) {
  expect_xyz_error("1 2 3\n1 2\n", 2, "found 2");
  expect_xyz_error("# c\n\n1 2 3\n4 5 6 7\n", 4, "found 4");
  expect_xyz_error("1,2,3\n", 1, "found 1");
  expect_xyz_error("1 2 3\n4 5 6 # 7 8\n\n7\r\n", 4, "found 1");
}

TEST(Xyz, BadTokensNameLineAndToken) {
  expect_xyz_error("1 2 3\n1 2 abc\n", 2, "'abc' is not a number");
  expect_xyz_error("1 2 3x\n", 1, "'3x' is not a number");
  expect_xyz_error("1 -- 3\n", 1, "'--' is not a number");
  expect_xyz_error("0x10 2 3\n", 1, "'0x10' is not a number");
  expect_xyz_error("1 2 1e999\n", 1, "out of the range");
}

TEST(Xyz, NonFiniteRejectedWithLine) {
  expect_xyz_error("1 2 3\n\n1 2 nan\n", 3, "non-finite");
  expect_xyz_error("NaN 2 3\n", 1, "non-finite");
  expect_xyz_error("1 2 3\n1 inf 3\n", 2, "non-finite");
  expect_xyz_error("1 2 -inf\n", 1, "non-finite");
  expect_xyz_error("1 2 Infinity\n", 1, "non-finite");
}

TEST(Xyz, WriteErrors) {
  const std::string dir = scratch(".d");  // never created
  EXPECT_THROW(write_xyz(PointSet{}, dir + "/out.xyz"), OutputError);
  EXPECT_FALSE(fs::exists(dir));

  PointSet bad;
  bad.push_back(0, std::nan(""), 0);
  const std::string path = scratch(".xyz");
  EXPECT_THROW(write_xyz(bad, path), UsageError);
  EXPECT_FALSE(fs::exists(path));
}

// A million points round-trip bit for bit (speed belongs to benchmarks, not to this test).
TEST(Xyz, MillionPointsRoundTrip) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  PointSet p;
  p.xyz.resize(3'000'000);
  for (double& x : p.xyz) x = u(rng);
  const std::string path = scratch(".xyz");
  write_xyz(p, path);
  const PointSet q = read_xyz(path);
  EXPECT_TRUE(q.xyz == p.xyz);  // == on doubles; no -0.0 or NaN in a uniform sample
  fs::remove(path);
}

// ---------------------------------------------------------------------------------------------
// TetGen .node
// ---------------------------------------------------------------------------------------------

TEST(Node, ZeroBased) {
  const std::string path = write_file(".node",
                                      "# written by hand\n"
                                      "3 3 0 0\n"
                                      "0 1 2 3\n"
                                      "\n"
                                      "1 4 5 6   # comment\n"
                                      "2 -7 8.5 9e1\n"
                                      "# trailing comment\n");
  expect_points(read_tetgen_node(path), {1, 2, 3, 4, 5, 6, -7, 8.5, 90});
}

TEST(Node, OneBasedWithAttributesAndMarkersIgnored) {
  const std::string path = write_file(".node",
                                      "2  3  2  1\r\n"
                                      "1  0.5 0.25 0.125  10 -20  7\r\n"
                                      "2  1e-300 -0 3  1.5 2.5  0\r\n");
  expect_points(read_tetgen_node(path), {0.5, 0.25, 0.125, 1e-300, -0.0, 3});
}

TEST(Node, EmptyDeclaration) {
  EXPECT_TRUE(read_tetgen_node(write_file(".node", "0 3 0 0\n")).empty());
  EXPECT_TRUE(read_tetgen_node(write_file(".node", "# nothing\n")).empty());
}

TEST(Node, Errors) {
  auto expect_node_error = [](const std::string& content, std::uint64_t line,
                              const std::string& needle) {
    const std::string path = write_file(".node", content);
    expect_input_error([&] { read_tetgen_node(path); }, path, line, needle);
  };
  expect_node_error("# c\n2 2 0 0\n0 1 2\n1 3 4\n", 2, "dimension is 2, must be 3");
  expect_node_error("2 3 0\n0 1 2 3\n1 3 4 5\n", 1, "bad .node header");
  expect_node_error("2 3 0 2\n", 1, "must be 0 or 1");
  expect_node_error("3 3 0 0\n0 1 2 3\n1 1 2 3\n3 1 2 3\n", 4, "out of sequence (expected 2)");
  expect_node_error("2 3 0 0\n1 1 2 3\n1 1 2 3\n", 3, "out of sequence (expected 2)");
  expect_node_error("2 3 0 0\n5 1 2 3\n6 1 2 3\n", 2, "first point index is 5");
  expect_node_error("2 3 0 0\nx 1 2 3\n1 1 2 3\n", 2, "'x' is not an integer");
  expect_node_error("3 3 0 0\n0 1 2 3\n1 1 2 3\n# the end\n", 0, "found only 2");
  expect_node_error("2 3 1 1\n0 1 2 3 9 1\n1 1 2 3 9\n", 3, "expected 6 fields");
  expect_node_error("2 3 0 0\n0 1 2 3\n1 1 nan 3\n", 3, "non-finite");
  expect_node_error("1 3 0 0\n0 1 2 3\n1 1 2 3\n", 3, "unexpected data after the 1 points");
}

// ---------------------------------------------------------------------------------------------
// PLY — fixtures are written by a small encoder here, from the same values the test expects.
// ---------------------------------------------------------------------------------------------

enum class Fmt { ascii, le, be };

struct Prop {
  std::string type;  ///< scalar type, or the item type of a list
  std::string name;
  std::string count_type;  ///< non-empty: a list property
};

/// One element: its properties and records. A record lists its values in property order; a
/// list property contributes its length followed by its items.
struct Elem {
  std::string name;
  std::vector<Prop> props;
  std::vector<std::vector<double>> records;
};

/// `v` encoded as the PLY type `type` in byte order `fmt`.
std::string encode(double v, const std::string& type, Fmt fmt) {
  auto raw = [&](auto x) {
    std::string b(sizeof x, '\0');
    std::memcpy(b.data(), &x, sizeof x);
    if ((fmt == Fmt::be) == (std::endian::native == std::endian::little))
      std::reverse(b.begin(), b.end());
    return b;
  };
  if (type == "char" || type == "int8") return raw(std::int8_t(v));
  if (type == "uchar" || type == "uint8") return raw(std::uint8_t(v));
  if (type == "short" || type == "int16") return raw(std::int16_t(v));
  if (type == "ushort" || type == "uint16") return raw(std::uint16_t(v));
  if (type == "int" || type == "int32") return raw(std::int32_t(v));
  if (type == "uint" || type == "uint32") return raw(std::uint32_t(v));
  if (type == "float" || type == "float32") return raw(float(v));
  if (type == "double" || type == "float64") return raw(v);
  ADD_FAILURE() << "test encoder: unknown type " << type;
  return {};
}

/// `v` as the PLY type `type` holds it (what a reader must return). The test gives integer
/// types only integer values in their range, which they hold exactly.
double as_type(double v, const std::string& type) {
  return type == "float" || type == "float32" ? double(float(v)) : v;
}

std::string ply_header(Fmt fmt, const std::vector<Elem>& elems, const std::string& extra = "") {
  std::string h = "ply\nformat ";
  h += fmt == Fmt::ascii ? "ascii" : fmt == Fmt::le ? "binary_little_endian" : "binary_big_endian";
  h += " 1.0\ncomment made by test_io_points\nobj_info nothing\n" + extra;
  for (const Elem& e : elems) {
    h += "element " + e.name + " " + std::to_string(e.records.size()) + "\n";
    for (const Prop& p : e.props)
      h += p.count_type.empty()
               ? "property " + p.type + " " + p.name + "\n"
               : "property list " + p.count_type + " " + p.type + " " + p.name + "\n";
  }
  return h + "end_header\n";
}

std::string ply_file(Fmt fmt, const std::vector<Elem>& elems) {
  std::string out = ply_header(fmt, elems);
  for (const Elem& e : elems)
    for (const std::vector<double>& r : e.records) {
      std::size_t k = 0;
      auto put = [&](double v, const std::string& type) {
        if (fmt == Fmt::ascii) {
          char buf[32];
          if (k) out += ' ';
          out.append(buf, std::to_chars(buf, buf + sizeof buf, as_type(v, type)).ptr);
        } else {
          out += encode(v, type, fmt);
        }
      };
      for (const Prop& p : e.props) {
        if (p.count_type.empty()) {
          put(r[k], p.type);
          ++k;
        } else {
          const std::size_t n = std::size_t(r[k]);
          put(r[k], p.count_type);
          ++k;
          for (std::size_t j = 0; j < n; ++j, ++k) put(r[k], p.type);
        }
      }
      if (fmt == Fmt::ascii) out += "\n";
    }
  return out;
}

/// A vertex element with coordinates of `type`, surrounded by normals and colours; `coords`
/// receives the coordinates a reader must return.
Elem vertex_element(const std::string& type, std::vector<double>& coords) {
  const bool integer =
      type != "float" && type != "float32" && type != "double" && type != "float64";
  const std::vector<double> values =
      integer ? std::vector<double>{0, 1, 2, 100, 7, 3, 12, 0, 9, 1, 1, 1}
              : std::vector<double>{1.0 / 3.0, -2.5e-10, 1e30,   0.1 + 0.2, -0.0, 7.0,
                                    1e-300,    5e-324,   -1e300, 4,         5,    6};
  Elem v{"vertex",
         {{"float", "nx", ""},
          {type, "x", ""},
          {"uchar", "red", ""},
          {type, "y", ""},
          {"double", "quality", ""},
          {type, "z", ""},
          {"int", "tags", "uchar"}},
         {}};
  coords.clear();
  for (std::size_t i = 0; i < values.size() / 3; ++i) {
    const double x = values[3 * i], y = values[3 * i + 1], z = values[3 * i + 2];
    const double tags = double(i % 3);
    std::vector<double> rec = {0.5, x, double(200 + i), y, -1.25, z, tags};
    for (std::size_t j = 0; j < i % 3; ++j) rec.push_back(double(j));
    v.records.push_back(rec);
    // Float types cannot hold 1e-300 or 1e300: skip those records for them.
    if ((type == "float" || type == "float32") &&
        (std::abs(x) > 1e38 || std::abs(y) > 1e38 || std::abs(z) > 1e38 ||
         (x != 0 && std::abs(x) < 1e-38) || (y != 0 && std::abs(y) < 1e-38) ||
         (z != 0 && std::abs(z) < 1e-38))) {
      v.records.pop_back();
      continue;
    }
    for (double c : {x, y, z}) coords.push_back(as_type(c, type));
  }
  return v;
}

/// Faces (with two list properties) and an edge element, to be placed before the vertices.
std::vector<Elem> leading_elements() {
  return {
      Elem{
          "face",
          {{"int", "vertex_indices", "uchar"},
           {"uchar", "flags", ""},
           {"float", "texcoord", "uint"}},
          {{3, 0, 1, 2, 9, 6, 0.5, 0.5, 1, 0, 0, 1}, {4, 0, 1, 2, 3, 1, 0}, {0, 2, 2, 0.25, 0.75}}},
      Elem{"edge", {{"int", "vertex1", ""}, {"int", "vertex2", ""}}, {{0, 1}, {1, 2}}}};
}

const char* fmt_name(Fmt f) { return f == Fmt::ascii ? "ascii" : f == Fmt::le ? "LE" : "BE"; }

TEST(Ply, AllFormatsAndCoordinateTypesRoundTrip) {
  for (Fmt fmt : {Fmt::ascii, Fmt::le, Fmt::be})
    for (const std::string type : {"float", "double", "float32", "float64", "int", "int32", "short",
                                   "uint16", "uchar", "int8", "uint", "ushort"}) {
      SCOPED_TRACE(std::string(fmt_name(fmt)) + " " + type);
      std::vector<double> coords;
      std::vector<Elem> elems = leading_elements();
      elems.push_back(vertex_element(type, coords));
      elems.push_back(
          Elem{"face2", {{"int", "vertex_indices", "uchar"}}, {{3, 0, 1, 2}}});  // after vertex
      const std::string path = write_file(".ply", ply_file(fmt, elems));
      ASSERT_GE(coords.size(), 9u);
      expect_points(read_ply_points(path), coords);
      expect_points(read_points(path), coords);
    }
}

TEST(Ply, AsciiWithCrlfHeaderAndBlankLines) {
  const std::string path =
      write_file(".ply",
                 "ply\r\nformat ascii 1.0\r\nelement vertex 2\r\n"
                 "property double x\r\nproperty double y\r\nproperty double z\r\n"
                 "end_header\r\n1 2 3\r\n\r\n-4.5 5e-1 6\r\n");
  expect_points(read_ply_points(path), {1, 2, 3, -4.5, 0.5, 6});
}

TEST(Ply, EmptyVertexElement) {
  std::vector<double> coords;
  Elem v = vertex_element("float", coords);
  v.records.clear();
  for (Fmt fmt : {Fmt::ascii, Fmt::le})
    EXPECT_TRUE(read_ply_points(write_file(".ply", ply_file(fmt, {v}))).empty());
}

TEST(Ply, TruncatedBinaryNamesElementAndRecord) {
  std::vector<double> coords;
  std::vector<Elem> elems = leading_elements();
  elems.push_back(vertex_element("double", coords));
  const std::size_t n = elems.back().records.size();
  for (Fmt fmt : {Fmt::le, Fmt::be}) {
    const std::string full = ply_file(fmt, elems);
    // Cut inside the last vertex record: the reader must say which.
    std::string path = write_file(".ply", full.substr(0, full.size() - 3));
    expect_input_error([&] { read_ply_points(path); }, path, 0,
                       "element 'vertex' record " + std::to_string(n - 1) + " (0-based)");
    // Cut inside the leading face element.
    const std::size_t header = ply_header(fmt, elems).size();
    path = write_file(".ply", full.substr(0, header + 20));
    expect_input_error([&] { read_ply_points(path); }, path, 0, "truncated");
  }
}

TEST(Ply, TruncatedAscii) {
  std::vector<double> coords;
  const std::string full = ply_file(Fmt::ascii, {vertex_element("double", coords)});
  const std::string path =
      write_file(".ply", full.substr(0, full.rfind('\n', full.size() - 2) + 1));
  expect_input_error([&] { read_ply_points(path); }, path, 0, "truncated");
}

TEST(Ply, ImplausibleCountFailsFastWithoutAllocating) {
  const std::string props = "property float x\nproperty float y\nproperty float z\n";
  for (const std::string fmt : {"binary_little_endian", "binary_big_endian", "ascii"}) {
    SCOPED_TRACE(fmt);
    const std::string path =
        write_file(".ply", "ply\nformat " + fmt + " 1.0\nelement vertex 4000000000\n" + props +
                               "end_header\n" + std::string(240, fmt == "ascii" ? '1' : '\0'));
    // Reading 4e9 points would throw std::bad_alloc (or allocate 96 GB), not this InputError
    // from the header check; the fuzz targets also run with -malloc_limit_mb=512.
    expect_input_error([&] { read_ply_points(path); }, path, 3, "declares 4000000000 records");
  }
  // The same for an element before the vertices.
  const std::string path =
      write_file(".ply",
                 "ply\nformat binary_little_endian 1.0\nelement face 4000000000\n"
                 "property list uchar int vertex_indices\nelement vertex 1\n" +
                     props + "end_header\n" + std::string(64, '\0'));
  expect_input_error([&] { read_ply_points(path); }, path, 3, "element 'face' declares 4000000000");
}

TEST(Ply, HeaderErrors) {
  auto expect_ply_error = [](const std::string& content, std::uint64_t line,
                             const std::string& needle) {
    const std::string path = write_file(".ply", content);
    expect_input_error([&] { read_ply_points(path); }, path, line, needle);
  };
  const std::string start = "ply\nformat ascii 1.0\n";
  const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
  expect_ply_error("plx\n", 1, "not a PLY file");
  expect_ply_error(
      start + "element vertex 1\nproperty float y\nproperty float z\nend_header\n1 2\n", 3,
      "no property 'x'");
  expect_ply_error(start + "element point 1\n" + xyz + "end_header\n1 2 3\n", 0,
                   "no 'vertex' element");
  expect_ply_error(start + "element vertex 1\nproperty float x\nproperty float\nend_header\n", 5,
                   "bad PLY header line 'property float'");
  expect_ply_error(start + "element vertex 1\nproperty float128 x\nend_header\n", 4,
                   "unknown type 'float128'");
  expect_ply_error(start + "element vertex 1\nproperty list float int x\nend_header\n", 4,
                   "not an integer type");
  expect_ply_error(start + "element vertex -1\n" + xyz + "end_header\n", 3, "non-negative count");
  expect_ply_error(start + "property float x\n", 3, "before any element");
  expect_ply_error(start + "element vertex 1\n" + xyz + "bogus line\nend_header\n", 7,
                   "unknown keyword 'bogus'");
  expect_ply_error("ply\nformat binary_middle_endian 1.0\nend_header\n", 2, "unknown format");
  expect_ply_error("ply\nformat ascii 2.0\nend_header\n", 2, "unsupported PLY version");
  expect_ply_error("ply\nelement vertex 0\n" + xyz + "end_header\n", 0, "no 'format' line");
  expect_ply_error(start + "element vertex 1\n" + xyz, 0, "no 'end_header'");
}

TEST(Ply, DataErrors) {
  auto expect_ply_error = [](const std::string& content, std::uint64_t line,
                             const std::string& needle) {
    const std::string path = write_file(".ply", content);
    expect_input_error([&] { read_ply_points(path); }, path, line, needle);
  };
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n";  // 7 header lines
  expect_ply_error(head + "1 2 3\n1 nan 3\n", 9, "non-finite");
  expect_ply_error(head + "1 2 3\n10 20\n", 9, "too few values");
  expect_ply_error(head + "1 2 3 4\n1 2 3\n", 8, "1 value(s) more");
  expect_ply_error(head + "1 2 3\n1 2 z\n", 9, "'z' is not a number");

  Elem v{"vertex",
         {{"double", "x", ""}, {"double", "y", ""}, {"double", "z", ""}},
         {{1, 2, 3}, {4, 5, 6}}};
  std::string bin = ply_file(Fmt::le, {v});
  const double inf = std::numeric_limits<double>::infinity();
  std::memcpy(bin.data() + bin.size() - 8, &inf, 8);  // z of vertex 1 (little-endian host)
  const std::string path = write_file(".ply", bin);
  expect_input_error([&] { read_ply_points(path); }, path, 0,
                     "non-finite coordinate z of vertex 1");
}

// ---------------------------------------------------------------------------------------------
// Dispatch and file-level errors
// ---------------------------------------------------------------------------------------------

TEST(ReadPoints, DispatchesOnCaseInsensitiveExtension) {
  const std::vector<double> want = {1, 2, 3, 4, 5, 6};
  expect_points(read_points(write_file(".xyz", "1 2 3\n4 5 6\n")), want);
  expect_points(read_points(write_file(".XyZ", "1 2 3\n4 5 6\n")), want);
  expect_points(read_points(write_file(".NODE", "2 3 0 0\n0 1 2 3\n1 4 5 6\n")), want);
  expect_points(
      read_points(write_file(".Ply",
                             "ply\nformat ascii 1.0\nelement vertex 2\nproperty int x\n"
                             "property int y\nproperty int z\nend_header\n1 2 3\n4 5 6\n")),
      want);
}

TEST(ReadPoints, UnknownExtension) {
  for (const std::string ext : {".txt", ".xyz.gz", ""}) {
    const std::string path = write_file(ext, "1 2 3\n");
    expect_input_error([&] { read_points(path); }, path, 0, "supported: .xyz, .node, .ply");
  }
}

TEST(ReadPoints, MissingOrUnreadableFile) {
  const std::string missing = scratch(".xyz");
  for (auto* reader : {&read_points, &read_xyz, &read_tetgen_node, &read_ply_points})
    expect_input_error([&] { reader(missing); }, missing, 0, std::strerror(ENOENT));
  const std::string dir = scratch(".xyz");
  fs::create_directories(dir);
  expect_input_error([&] { read_xyz(dir); }, dir, 0, "is a directory");
}

}  // namespace
}  // namespace kdmesh
