// kdmesh — Exodus II writer: read back through the Exodus C API (counts, nodes, blocks per
// region, side sets with their side numbers, node sets, names), atomic replacement and errors.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <vtk_exodusII.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/fe_mesh.h"
#include "io/exodus_writer.h"
#include "tests/support/clients.h"
#include "tests/support/fe_cube.h"
#include "tests/support/scratch.h"

namespace kdmesh {
namespace {

namespace fs = std::filesystem;
using namespace test;

std::string scratch(const std::string& ext) { return scratch_path("io_exodus", ext); }

/// The Exodus manual's side listings (1-based corners, counterclockwise seen from outside):
/// written out here independently of the writer's table.
constexpr int kManualSide[4][3] = {{1, 2, 4}, {2, 3, 4}, {1, 4, 3}, {1, 3, 2}};

struct ExoSet {
  std::string name;
  std::vector<int> entries, extra;
};

struct ExoBlock {
  std::string name, type;
  int elements = 0, nodes_per_element = 0;
  std::vector<int> conn;
};

/// Everything the writer puts in the file, read through the Exodus C API.
struct ExoFile {
  std::string title;
  int dim = 0, nodes = 0, elements = 0;
  std::vector<double> x, y, z;
  std::map<int, ExoBlock> blocks;  ///< by block id, in file order in block_ids
  std::vector<int> block_ids, elem_num_map;
  std::map<int, ExoSet> side_sets, node_sets;
};

std::vector<std::string> read_names(int exo, ex_entity_type type, std::size_t n) {
  std::vector<std::vector<char>> buf(n, std::vector<char>(257, '\0'));
  std::vector<char*> ptrs;
  for (auto& b : buf) ptrs.push_back(b.data());
  std::vector<std::string> out;
  if (n == 0) return out;
  EXPECT_GE(ex_get_names(exo, type, ptrs.data()), 0);
  for (auto& b : buf) out.emplace_back(b.data());
  return out;
}

std::map<int, ExoSet> read_sets(int exo, ex_entity_type type, int count) {
  std::map<int, ExoSet> out;
  std::vector<int> ids(std::size_t(count), 0);
  if (count == 0) return out;
  EXPECT_GE(ex_get_ids(exo, type, ids.data()), 0);
  const std::vector<std::string> names = read_names(exo, type, ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) {
    int n = 0, df = 0;
    EXPECT_GE(ex_get_set_param(exo, type, ids[i], &n, &df), 0);
    EXPECT_EQ(df, 0);
    ExoSet s;
    s.name = names[i];
    s.entries.resize(std::size_t(n));
    if (type == EX_SIDE_SET) s.extra.resize(std::size_t(n));
    EXPECT_GE(ex_get_set(exo, type, ids[i], s.entries.data(), type == EX_SIDE_SET ? s.extra.data() : nullptr), 0);
    out[ids[i]] = s;
  }
  return out;
}

ExoFile read_exodus(const std::string& path) {
  ExoFile f;
  int cpu_ws = sizeof(double), io_ws = 0;
  float version = 0;
  const int exo = ex_open(path.c_str(), EX_READ, &cpu_ws, &io_ws, &version);
  EXPECT_GE(exo, 0) << path;
  if (exo < 0) return f;
  ex_set_option(exo, EX_OPT_MAX_NAME_LENGTH, 256);
  char title[MAX_LINE_LENGTH + 1] = {0};
  int nblk = 0, nns = 0, nss = 0;
  EXPECT_GE(ex_get_init(exo, title, &f.dim, &f.nodes, &f.elements, &nblk, &nns, &nss), 0);
  f.title = title;
  f.x.resize(std::size_t(f.nodes));
  f.y.resize(std::size_t(f.nodes));
  f.z.resize(std::size_t(f.nodes));
  EXPECT_GE(ex_get_coord(exo, f.x.data(), f.y.data(), f.z.data()), 0);
  f.block_ids.resize(std::size_t(nblk));
  if (nblk) {
    EXPECT_GE(ex_get_ids(exo, EX_ELEM_BLOCK, f.block_ids.data()), 0);
  }
  const std::vector<std::string> names = read_names(exo, EX_ELEM_BLOCK, std::size_t(nblk));
  for (std::size_t i = 0; i < f.block_ids.size(); ++i) {
    ExoBlock b;
    char type[MAX_STR_LENGTH + 1] = {0};
    int edges = 0, faces = 0, attrs = 0;
    EXPECT_GE(ex_get_block(exo, EX_ELEM_BLOCK, f.block_ids[i], type, &b.elements, &b.nodes_per_element, &edges,
                           &faces, &attrs),
              0);
    b.type = type;
    b.name = names[i];
    b.conn.resize(std::size_t(b.elements) * std::size_t(b.nodes_per_element));
    EXPECT_GE(ex_get_conn(exo, EX_ELEM_BLOCK, f.block_ids[i], b.conn.data(), nullptr, nullptr), 0);
    f.blocks[f.block_ids[i]] = b;
  }
  f.elem_num_map.resize(std::size_t(f.elements));
  EXPECT_GE(ex_get_id_map(exo, EX_ELEM_MAP, f.elem_num_map.data()), 0);
  f.side_sets = read_sets(exo, EX_SIDE_SET, nss);
  f.node_sets = read_sets(exo, EX_NODE_SET, nns);
  ex_close(exo);
  return f;
}

/// The corners (0-based point ids) of element `e` (1-based, in the file's numbering).
std::vector<int> element_corners(const ExoFile& f, int e) {
  int first = 1;
  for (const int id : f.block_ids) {
    const ExoBlock& b = f.blocks.at(id);
    if (e < first + b.elements) {
      const int* c = b.conn.data() + std::size_t(e - first) * std::size_t(b.nodes_per_element);
      return {c[0] - 1, c[1] - 1, c[2] - 1, c[3] - 1};
    }
    first += b.elements;
  }
  ADD_FAILURE() << "element " << e << " is in no block";
  return {0, 0, 0, 0};
}

std::size_t group_face_count(const FeMesh& m, const std::string& name) {
  for (const FeGroup& g : m.groups)
    if (g.name == name) {
      std::size_t n = 0;
      for (std::size_t f = 0; f < m.face_entity.size(); ++f)
        n += std::count(g.entities.begin(), g.entities.end(), m.face_entity[f]) > 0;
      return n;
    }
  ADD_FAILURE() << "no group " << name;
  return 0;
}

TEST(ExodusFormat, SideNumbersOfTheUnitTetFollowTheManual) {
  // the unit tet (0,0,0) (1,0,0) (0,1,0) (0,0,1): side 1 is y = 0 (corners 1 2 4), side 2 the
  // slanted face (2 3 4), side 3 x = 0 (1 4 3), side 4 z = 0 (1 3 2)
  const std::uint32_t tet[4] = {10, 11, 12, 13};
  EXPECT_EQ(exodus_side_number(tet, 10, 11, 13), 1);
  EXPECT_EQ(exodus_side_number(tet, 13, 12, 11), 2);
  EXPECT_EQ(exodus_side_number(tet, 12, 10, 13), 3);
  EXPECT_EQ(exodus_side_number(tet, 11, 10, 12), 4);
  EXPECT_EQ(exodus_side_number(tet, 10, 11, 99), 0);

  // the same through a file: one group per face of one tet
  FeMesh m;
  m.points.push_back(0, 0, 0);
  m.points.push_back(1, 0, 0);
  m.points.push_back(0, 1, 0);
  m.points.push_back(0, 0, 1);
  m.tets = {0, 1, 2, 3};
  m.tet_entity = {0};
  m.faces = {0, 1, 3, /**/ 1, 2, 3, /**/ 0, 3, 2, /**/ 0, 2, 1};  // outward
  m.face_entity = {0, 1, 2, 3};
  m.groups = {{"y0", 2, {0}}, {"slanted", 2, {1}}, {"x0", 2, {2}}, {"z0", 2, {3}}};
  const std::string path = scratch(".exo");
  write_exodus(m, path);
  const ExoFile f = read_exodus(path);
  ASSERT_EQ(f.side_sets.size(), 4u);
  const std::map<std::string, int> want = {{"y0", 1}, {"slanted", 2}, {"x0", 3}, {"z0", 4}};
  for (const auto& [id, s] : f.side_sets) {
    ASSERT_EQ(s.entries.size(), 1u) << s.name;
    EXPECT_EQ(s.entries[0], 1);
    EXPECT_EQ(s.extra[0], want.at(s.name)) << s.name;
  }
}

TEST(ExodusFormat, CubeReadsBackThroughTheExodusApi) {
  for (const int order : {1, 2}) {
    SCOPED_TRACE(order);
    const FeMesh mesh = cube_mesh(2, order);
    const std::string path = scratch(".exo");
    write_exodus(mesh, path);
    const ExoFile f = read_exodus(path);
    const int tn = mesh.tet_nodes();

    EXPECT_EQ(f.title, "kdmesh");
    EXPECT_EQ(f.dim, 3);
    ASSERT_EQ(std::size_t(f.nodes), mesh.points.size());
    ASSERT_EQ(std::size_t(f.elements), mesh.num_tets());
    // a known node: grid point (2, 1, 0) of the n = 2 cube is at (1, 0.5, 0)
    const std::uint32_t known = cube_vid(2, 2, 1, 0);
    EXPECT_EQ(f.x[known], 1.0);
    EXPECT_EQ(f.y[known], 0.5);
    EXPECT_EQ(f.z[known], 0.0);

    // one block per region: id = region + 1, named after the dim-3 group of exactly that region
    ASSERT_EQ(f.block_ids, (std::vector<int>{int(kLeftVolume) + 1, int(kRightVolume) + 1}));
    std::map<std::uint32_t, int> per_region;
    for (const std::uint32_t r : mesh.tet_entity) ++per_region[r];
    const ExoBlock& left = f.blocks.at(int(kLeftVolume) + 1);
    const ExoBlock& right = f.blocks.at(int(kRightVolume) + 1);
    EXPECT_EQ(left.elements, per_region[kLeftVolume]);
    EXPECT_EQ(right.elements, per_region[kRightVolume]);
    EXPECT_EQ(left.elements, 24);
    EXPECT_EQ(left.name, "region_0");
    EXPECT_EQ(right.name, "right_half");
    for (const ExoBlock* b : {&left, &right}) {
      EXPECT_EQ(b->type, order == 2 ? "TETRA10" : "TETRA");
      EXPECT_EQ(b->nodes_per_element, tn);
    }
    // the element number map gives kdmesh's tet; its nodes are FeMesh's in FeMesh's (= Exodus')
    // order, and the tet's region is the block's
    int e = 0;
    for (const int id : f.block_ids) {
      const ExoBlock& b = f.blocks.at(id);
      for (int i = 0; i < b.elements; ++i, ++e) {
        const std::size_t t = std::size_t(f.elem_num_map[std::size_t(e)] - 1);
        ASSERT_LT(t, mesh.num_tets());
        EXPECT_EQ(int(mesh.tet_entity[t]) + 1, id);
        for (int k = 0; k < tn; ++k)
          EXPECT_EQ(b.conn[std::size_t(i * tn + k)], int(mesh.tets[t * std::size_t(tn) + std::size_t(k)]) + 1);
      }
    }
    std::vector<int> sorted_map = f.elem_num_map;
    std::sort(sorted_map.begin(), sorted_map.end());
    for (std::size_t i = 0; i < sorted_map.size(); ++i) EXPECT_EQ(sorted_map[i], int(i) + 1);

    // side sets: one per dim-2 group, id = position + 1, as many sides as the group has faces;
    // each (element, side) is a group face, listed by the manual with an outward normal
    std::size_t dim2 = 0;
    for (std::size_t g = 0; g < mesh.groups.size(); ++g) {
      const FeGroup& grp = mesh.groups[g];
      if (grp.dim != 2) continue;
      ++dim2;
      SCOPED_TRACE(grp.name);
      ASSERT_TRUE(f.side_sets.count(int(g) + 1));
      const ExoSet& s = f.side_sets.at(int(g) + 1);
      EXPECT_EQ(s.name, grp.name);
      EXPECT_EQ(s.entries.size(), group_face_count(mesh, grp.name));
      std::set<std::array<std::uint32_t, 3>> group_faces;
      std::map<std::array<std::uint32_t, 3>, std::size_t> face_of;
      for (std::size_t fc = 0; fc < mesh.face_entity.size(); ++fc)
        if (std::count(grp.entities.begin(), grp.entities.end(), mesh.face_entity[fc])) {
          const std::uint32_t* c = &mesh.faces[fc * std::size_t(mesh.face_nodes())];
          face_of[sorted3(c[0], c[1], c[2])] = fc;
        }
      std::set<std::array<std::uint32_t, 3>> seen;
      for (std::size_t i = 0; i < s.entries.size(); ++i) {
        const std::vector<int> c = element_corners(f, s.entries[i]);
        ASSERT_GE(s.extra[i], 1);
        ASSERT_LE(s.extra[i], 4);
        const int* side = kManualSide[s.extra[i] - 1];
        const std::uint32_t a = std::uint32_t(c[std::size_t(side[0] - 1)]),
                            b = std::uint32_t(c[std::size_t(side[1] - 1)]),
                            d = std::uint32_t(c[std::size_t(side[2] - 1)]);
        const auto key = sorted3(a, b, d);
        ASSERT_TRUE(face_of.count(key)) << "side " << s.extra[i] << " of element " << s.entries[i];
        seen.insert(key);
        // outward: the manual's listing turns like the mesh face (whose normal points out)
        const std::uint32_t* fcn = &mesh.faces[face_of[key] * std::size_t(mesh.face_nodes())];
        const bool same = (fcn[0] == a && fcn[1] == b && fcn[2] == d) || (fcn[0] == b && fcn[1] == d && fcn[2] == a) ||
                          (fcn[0] == d && fcn[1] == a && fcn[2] == b);
        EXPECT_TRUE(same) << "side " << s.extra[i] << " of element " << s.entries[i] << " is not outward";
      }
      EXPECT_EQ(seen.size(), face_of.size());
    }
    EXPECT_EQ(f.side_sets.size(), dim2);

    // a known face: the top z = 1 of the n = 2 cube, 8 triangles, each on a tet of the top
    // subcubes; its three corners by the manual's listing all lie at z = 1
    const ExoSet& zmax = f.side_sets.at(2 + 5 + 1);  // groups: solid, right_half, xmin..zmax
    ASSERT_EQ(zmax.name, "zmax");
    EXPECT_EQ(zmax.entries.size(), 8u);
    std::map<int, int> side_histogram;
    for (std::size_t i = 0; i < zmax.entries.size(); ++i) {
      const std::vector<int> c = element_corners(f, zmax.entries[i]);
      const int* side = kManualSide[zmax.extra[i] - 1];
      for (int k = 0; k < 3; ++k) EXPECT_EQ(f.z[std::size_t(c[std::size_t(side[k] - 1)])], 1.0);
      ++side_histogram[zmax.extra[i]];
    }
    // kuhn_cube's tet: c0 is the subcube's low corner (i, j, k), the only corner off z = 1 in a
    // tet with a top face, so that face is the one opposite corner 1: side 2 = (2 3 4)
    EXPECT_EQ(side_histogram, (std::map<int, int>{{2, 8}}));

    // the interface x = 1/2 is given on the left tets (its faces' normals point +x, out of them)
    const ExoSet& iface = f.side_sets.at(2 + 6 + 1 + 1);
    ASSERT_EQ(iface.name, "interface");
    for (const int el : iface.entries)
      EXPECT_EQ(mesh.tet_entity[std::size_t(f.elem_num_map[std::size_t(el - 1)] - 1)], kLeftVolume);

    // node sets: one per group (every dimension), id = position + 1, the group's nodes
    ASSERT_EQ(f.node_sets.size(), mesh.groups.size());
    const ExoSet& xmin = f.node_sets.at(2 + 1);
    EXPECT_EQ(xmin.name, "xmin");
    EXPECT_EQ(xmin.entries.size(), order == 2 ? 25u : 9u);
    for (const int n : xmin.entries) EXPECT_EQ(f.x[std::size_t(n - 1)], 0.0);
    EXPECT_TRUE(std::is_sorted(xmin.entries.begin(), xmin.entries.end()));
    const ExoSet& x_edges = f.node_sets.at(int(mesh.groups.size()) - 1);
    EXPECT_EQ(x_edges.name, "x_edges");
    EXPECT_EQ(x_edges.entries.size(), order == 2 ? 20u : 12u);  // 4 edges of 2 (4) segments
    EXPECT_EQ(f.node_sets.at(1).entries.size(), mesh.points.size());  // "solid": every node
  }
}

TEST(ExodusFormat, LongGroupNamesAreKept) {
  FeMesh mesh = cube_mesh(2, 1);
  const std::string name = "a_group_name_well_beyond_thirty_two_characters";
  mesh.groups[2].name = name;
  const std::string path = scratch(".exo");
  write_exodus(mesh, path);
  const ExoFile f = read_exodus(path);
  EXPECT_EQ(f.side_sets.at(3).name, name);
  EXPECT_EQ(f.node_sets.at(3).name, name);
}

TEST(ExodusFormat, UnwritablePathThrowsOutputErrorAndLeavesNoTemporary) {
  const FeMesh mesh = cube_mesh(2, 1);
  const fs::path dir = scratch("-dir");  // removed first: reruns start clean
  fs::create_directories(dir);
  expect_unwritable_refused<OutputError>(dir, "m.exo",
                                         [&](const std::string& p) { write_exodus(mesh, p); });
  // a directory or a symbolic link in the file's place is never replaced
  const std::string path = (dir / "m.exo").string();
  fs::create_directories(path);
  try {
    write_exodus(mesh, path);
    FAIL() << "no OutputError";
  } catch (const OutputError& e) {
    EXPECT_EQ(e.file(), path);
  }
  EXPECT_TRUE(fs::is_directory(path));
  fs::remove(path);
  fs::create_symlink("elsewhere.exo", path);
  EXPECT_THROW(write_exodus(mesh, path), OutputError);
  EXPECT_TRUE(fs::is_symlink(path));
  EXPECT_EQ(temporaries_in(dir), 0);
}

TEST(ExodusFormat, ReplacesRegularFilesAtomically) {
  const FeMesh mesh = cube_mesh(2, 1);
  const std::string path = scratch(".exo");
  write_text_file(path, "old");
  write_exodus(mesh, path);
  EXPECT_EQ(std::size_t(read_exodus(path).nodes), mesh.points.size());
  EXPECT_EQ(temporaries_in(fs::path(path).parent_path()), 0);
}

TEST(ExodusFormat, InvalidMeshIsAUsageError) {
  FeMesh mesh = cube_mesh(2, 1);
  mesh.tets[5] = std::uint32_t(mesh.points.size());  // node id out of range
  const std::string path = scratch(".exo");
  EXPECT_THROW(write_exodus(mesh, path), UsageError);
  EXPECT_FALSE(fs::exists(path));
  // a group face that no tet has
  FeMesh stray = cube_mesh(2, 1);
  stray.faces.insert(stray.faces.end(), {0, 4, 20});
  stray.face_entity.push_back(kSide0);
  EXPECT_THROW(write_exodus(stray, path), UsageError);
  EXPECT_FALSE(fs::exists(path));
}

}  // namespace
}  // namespace kdmesh
