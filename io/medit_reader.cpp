// kdmesh — MEDIT / Gamma Mesh Format (.mesh, ASCII) reader into FeMesh.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "io/medit_reader.h"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/error.h"
#include "io/file_io.h"
#include "io/text_scanner.h"

namespace kdmesh {

namespace {

struct Kind {
  std::string_view keyword;
  int dim;    ///< 1..3
  int order;  ///< 1 or 2
  int nodes;
};
constexpr Kind kKinds[] = {
    {"Edges", 1, 1, 2},      {"EdgesP2", 1, 2, 3},     {"Triangles", 2, 1, 3},
    {"TrianglesP2", 2, 2, 6}, {"Tetrahedra", 3, 1, 4}, {"TetrahedraP2", 3, 2, 10},
};

/// Sections skipped with the number of integer and real values per item.
struct Skipped {
  std::string_view keyword;
  int ints;
  int reals;
};
constexpr Skipped kSkipped[] = {
    {"Corners", 1, 0},          {"Ridges", 1, 0},           {"RequiredVertices", 1, 0},
    {"RequiredEdges", 1, 0},    {"RequiredTriangles", 1, 0}, {"RequiredTetrahedra", 1, 0},
    {"Normals", 0, 3},          {"Tangents", 0, 3},          {"NormalAtVertices", 2, 0},
    {"TangentAtVertices", 2, 0},
};

constexpr std::string_view kUnsupportedElements[] = {
    "Quadrilaterals", "Hexahedra", "Hexaedra", "Prisms", "Pyramids", "QuadrilateralsQ2",
    "HexahedraQ2", "TrianglesP3", "TetrahedraP3", "EdgesP3", "PrismsP2", "PyramidsP2"};

class MeditReader {
 public:
  MeditReader(std::string_view data, const std::string& path) : sc_(data, path) {}

  FeMesh read() {
    FeMesh mesh;
    bool have_version = false, have_dimension = false, have_vertices = false;
    std::set<std::string_view> seen;
    for (;;) {
      if (!skip_comments()) break;
      const std::string_view kw = sc_.token("a keyword");
      if (kw == "End") break;
      if (!have_version && kw != "MeshVersionFormatted")
        sc_.fail("expected 'MeshVersionFormatted' first, found " + quoted(kw) +
                 " (not a MEDIT .mesh file)");
      if (kw != "MeshVersionFormatted" && kw != "Dimension" && !seen.insert(kw).second)
        sc_.fail("second " + quoted(kw) + " section");
      if (kw == "MeshVersionFormatted") {
        if (have_version) sc_.fail("second MeshVersionFormatted");
        const std::int64_t v = sc_.int64("the format version");
        if (v < 1 || v > 4) sc_.fail("MeshVersionFormatted " + std::to_string(v) + " (1 to 4)");
        have_version = true;
      } else if (kw == "Dimension") {
        const std::int64_t d = sc_.int64("the dimension");
        if (d != 3) sc_.fail("Dimension " + std::to_string(d) + ": kdmesh reads 3D meshes only");
        have_dimension = true;
      } else if (kw == "Vertices") {
        if (!have_dimension) sc_.fail("Vertices before Dimension");
        const std::uint64_t n = sc_.count("the number of vertices", sc_.remaining() / 8);
        if (n > std::numeric_limits<std::uint32_t>::max()) sc_.fail("too many vertices");
        mesh.points.xyz.reserve(3 * n);
        for (std::uint64_t i = 0; i < n; ++i) {
          for (int c = 0; c < 3; ++c) mesh.points.xyz.push_back(sc_.real("a vertex coordinate"));
          sc_.int64("a vertex ref");
        }
        have_vertices = true;
      } else if (const Kind* k = find_kind(kw)) {
        if (!have_vertices) sc_.fail(std::string(kw) + " before Vertices");
        read_elements(mesh, *k);
      } else if (const Skipped* s = find_skipped(kw)) {
        const std::uint64_t n =
            sc_.count("the number of items", sc_.remaining() / (2 * std::size_t(s->ints + s->reals)));
        for (std::uint64_t i = 0; i < n; ++i) {
          for (int j = 0; j < s->ints; ++j) sc_.int64("an integer");
          for (int j = 0; j < s->reals; ++j) sc_.real("a number");
        }
      } else if (std::find(std::begin(kUnsupportedElements), std::end(kUnsupportedElements), kw) !=
                 std::end(kUnsupportedElements)) {
        sc_.fail(quoted(kw) + " elements are not supported (kdmesh reads tetrahedra, triangles "
                 "and edges)");
      } else {
        sc_.fail("unknown or unsupported keyword " + quoted(kw));
      }
    }
    if (!have_version) sc_.fail("empty file: no MeshVersionFormatted");
    mesh.order = order_ == 0 ? 1 : order_;
    for (auto& [key, ents] : groups_) {
      FeGroup g;
      g.dim = key.second;
      g.name = key.first;
      g.entities.assign(ents.begin(), ents.end());
      mesh.groups.push_back(std::move(g));
    }
    std::stable_sort(mesh.groups.begin(), mesh.groups.end(),
                     [&](const FeGroup& a, const FeGroup& b) {
                       return group_rank_.at({a.name, a.dim}) < group_rank_.at({b.name, b.dim});
                     });
    return mesh;
  }

 private:
  static const Kind* find_kind(std::string_view kw) {
    for (const Kind& k : kKinds)
      if (k.keyword == kw) return &k;
    return nullptr;
  }
  static const Skipped* find_skipped(std::string_view kw) {
    for (const Skipped& s : kSkipped)
      if (s.keyword == kw) return &s;
    return nullptr;
  }

  /// Consumes comment lines, reading "# kdmesh-group" ones; false at the end of the text.
  bool skip_comments() {
    while (sc_.peek() == '#') {
      const std::string_view line = sc_.rest_of_line();
      constexpr std::string_view kTag = "# kdmesh-group ";
      if (line.substr(0, kTag.size()) == kTag) read_group(line.substr(kTag.size()));
    }
    return sc_.more();
  }

  /// "<dim> <name> <ref> ..." of a group comment (the comment's line is sc_.line()).
  void read_group(std::string_view rest) {
    std::vector<std::string_view> tok;
    for (std::size_t i = 0; i < rest.size();) {
      while (i < rest.size() && (rest[i] == ' ' || rest[i] == '\t')) ++i;
      const std::size_t start = i;
      while (i < rest.size() && rest[i] != ' ' && rest[i] != '\t') ++i;
      if (i > start) tok.push_back(rest.substr(start, i - start));
    }
    std::int64_t dim = 0;
    if (tok.size() < 3 || !parse_int(tok[0], dim) || dim < 1 || dim > 3)
      sc_.fail("bad kdmesh-group comment: expected '<dim 1..3> <name> <ref> ...'");
    const std::pair<std::string, int> key{std::string(tok[1]), int(dim)};
    group_rank_.emplace(key, group_rank_.size());
    auto& ents = groups_[key];
    for (std::size_t i = 2; i < tok.size(); ++i) {
      std::int64_t ref = 0;
      if (!parse_int(tok[i], ref) || ref < 1 ||
          ref > std::int64_t(std::numeric_limits<std::uint32_t>::max()))
        sc_.fail("kdmesh-group ref " + quoted(tok[i]) + " is not an integer >= 1 (entity id + 1)");
      ents.insert(std::uint32_t(ref - 1));
    }
  }

  static bool parse_int(std::string_view t, std::int64_t& v) {
    const auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    return ec == std::errc() && p == t.data() + t.size();
  }

  void read_elements(FeMesh& mesh, const Kind& k) {
    if (order_ == 0) {
      order_ = k.order;
      first_ = k.keyword;
    } else if (order_ != k.order) {
      sc_.fail(std::string(k.keyword) + " after " + std::string(first_) +
               ": mixed element orders are not supported");
    }
    auto& conn = k.dim == 3 ? mesh.tets : k.dim == 2 ? mesh.faces : mesh.edges;
    auto& ent = k.dim == 3 ? mesh.tet_entity : k.dim == 2 ? mesh.face_entity : mesh.edge_entity;
    const std::uint64_t n =
        sc_.count("the number of elements", sc_.remaining() / (2 * std::size_t(k.nodes + 1)));
    const std::uint64_t nv = mesh.points.size();
    conn.reserve(conn.size() + n * std::size_t(k.nodes));
    ent.reserve(ent.size() + n);
    for (std::uint64_t i = 0; i < n; ++i) {
      for (int j = 0; j < k.nodes; ++j) {
        const std::int64_t v = sc_.int64("a vertex index");
        if (v < 1 || std::uint64_t(v) > nv)
          sc_.fail(std::string(k.keyword) + " element " + std::to_string(i + 1) +
                   ": vertex index " + std::to_string(v) + " is outside 1.." + std::to_string(nv));
        conn.push_back(std::uint32_t(v - 1));
      }
      const std::int64_t ref = sc_.int64("an element ref");
      if (ref < 1 || ref > std::int64_t(std::numeric_limits<std::uint32_t>::max()))
        sc_.fail(std::string(k.keyword) + " element " + std::to_string(i + 1) + ": ref " +
                 std::to_string(ref) + " (kdmesh needs refs >= 1: entity id = ref - 1)");
      ent.push_back(std::uint32_t(ref - 1));
    }
  }

  TextScanner sc_;
  int order_ = 0;
  std::string_view first_;
  std::map<std::pair<std::string, int>, std::set<std::uint32_t>> groups_;
  std::map<std::pair<std::string, int>, std::size_t> group_rank_;
};

}  // namespace

FeMesh read_medit(const std::string& path) {
  const std::string data = read_whole_file(path);
  MeditReader reader(data, path);
  return reader.read();
}

}  // namespace kdmesh
