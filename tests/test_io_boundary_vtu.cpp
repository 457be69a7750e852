// kdmesh — tests of the boundary VTU writer: what VTK's own reader gets back from an FeMesh.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>
#include <vtkCell.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/fe_mesh.h"
#include "io/boundary_vtu_writer.h"
#include "tests/support/fe_cube.h"
#include "tests/support/scratch.h"

namespace kdmesh {
namespace {

namespace fs = std::filesystem;

std::string scratch(const std::string& ext) { return test::scratch_path("io_boundary_vtu", ext); }

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Files beside `path` whose names start with its file name and ".tmp" (AtomicFile leftovers).
std::vector<std::string> leftover_temps(const std::string& path) {
  std::vector<std::string> found;
  const fs::path p(path);
  if (!fs::exists(p.parent_path())) return found;
  const std::string prefix = p.filename().string() + ".tmp";
  for (const auto& entry : fs::directory_iterator(p.parent_path()))
    if (entry.path().filename().string().rfind(prefix, 0) == 0) found.push_back(entry.path().string());
  return found;
}

constexpr std::uint32_t kPatch0 = 10;  // patches 10 (x = 0), 11 (x = 1), 12 (y = 0), ... 15 (z = 1)
constexpr std::uint32_t kCurve0 = 3;   // curves 3 .. 14: 4 * axis + 2 * s + t + kCurve0

/// The unit cube cut into n^3 subcubes, each split into 6 positive Kuhn tets; faces: the
/// boundary triangles with their outward orientation, entity kPatch0 + 2 * axis + side; edges:
/// the 12 cube edges (n segments each), entity kCurve0 + 4 * axis + 2 * s + t. Groups (checked
/// against their names below):
///   0 "solid" dim 3 (not written)            1 "xmin" dim 2 {x = 0}
///   2 "walls" dim 2 {x = 0, x = 1, y = 0}    3 "load" dim 2 {z = 1}
///   4 "load" dim 1 {the 4 edges along x}     5 "entity" dim 2 {y = 1, z = 0}
///   6 "corner_edges" dim 1 {curves 3 and 14}
/// With order 2: one mid-edge node per distinct edge, at its midpoint (FeMesh node order).
FeMesh cube(int n, int order) {
  FeMesh m = test::kuhn_cube(n);
  // Boundary faces: tet faces (outward listing) whose three corners lie on one cube side.
  static const int kOutward[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  for (std::size_t t = 0; t < m.tet_entity.size(); ++t)
    for (const auto& f : kOutward) {
      const std::uint32_t a = m.tets[4 * t + f[0]], b = m.tets[4 * t + f[1]], c = m.tets[4 * t + f[2]];
      for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side)
          if (m.points.p(a)[axis] == side && m.points.p(b)[axis] == side && m.points.p(c)[axis] == side) {
            m.faces.insert(m.faces.end(), {a, b, c});
            m.face_entity.push_back(kPatch0 + std::uint32_t(2 * axis + side));
          }
    }
  test::add_cube_edges(m, n, kCurve0);
  m.groups.push_back({"solid", 3, {0}});
  m.groups.push_back({"xmin", 2, {kPatch0}});
  m.groups.push_back({"walls", 2, {kPatch0, kPatch0 + 1, kPatch0 + 2}});
  m.groups.push_back({"load", 2, {kPatch0 + 5}});
  m.groups.push_back({"load", 1, {kCurve0, kCurve0 + 1, kCurve0 + 2, kCurve0 + 3}});
  m.groups.push_back({"entity", 2, {kPatch0 + 3, kPatch0 + 4}});
  m.groups.push_back({"corner_edges", 1, {kCurve0, kCurve0 + 11}});
  if (order == 2) test::make_quadratic(m);
  return m;
}

vtkSmartPointer<vtkUnstructuredGrid> read_back(const std::string& path) {
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  EXPECT_EQ(reader->GetErrorCode(), 0u) << path;
  return reader->GetOutput();
}

bool lists(const FeGroup& g, std::uint32_t entity) {
  return std::find(g.entities.begin(), g.entities.end(), entity) != g.entities.end();
}

/// Everything the file must hold, derived from `m` (see io/boundary_vtu_writer.h).
void expect_boundary_of(const FeMesh& m, vtkUnstructuredGrid* grid) {
  const std::size_t nf = m.num_faces(), ne = m.num_edges();
  const std::size_t fn = std::size_t(m.face_nodes()), en = std::size_t(m.edge_nodes());

  // Points: exactly the nodes of faces and edges, ascending, each at its coordinates.
  std::set<std::uint32_t> used(m.faces.begin(), m.faces.end());
  used.insert(m.edges.begin(), m.edges.end());
  ASSERT_EQ(std::size_t(grid->GetNumberOfPoints()), used.size());
  vtkDataArray* node_id = grid->GetPointData()->GetArray("node_id");
  ASSERT_NE(node_id, nullptr);
  EXPECT_EQ(node_id->GetDataType(), VTK_UNSIGNED_INT);
  std::vector<std::uint32_t> ids;
  for (vtkIdType p = 0; p < grid->GetNumberOfPoints(); ++p) {
    ids.push_back(std::uint32_t(node_id->GetTuple1(p)));
    double x[3];
    grid->GetPoint(p, x);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(x[c], m.points.p(ids.back())[c]) << "point " << p;
  }
  EXPECT_EQ(ids, std::vector<std::uint32_t>(used.begin(), used.end()));

  // Cells: faces then edges, same nodes in the same order, VTK types by order.
  ASSERT_EQ(std::size_t(grid->GetNumberOfCells()), nf + ne);
  const int tri = m.order == 2 ? VTK_QUADRATIC_TRIANGLE : VTK_TRIANGLE;
  const int line = m.order == 2 ? VTK_QUADRATIC_EDGE : VTK_LINE;
  vtkNew<vtkIdList> pts;
  for (std::size_t c = 0; c < nf + ne; ++c) {
    const bool face = c < nf;
    EXPECT_EQ(grid->GetCellType(vtkIdType(c)), face ? tri : line) << "cell " << c;
    grid->GetCellPoints(vtkIdType(c), pts);
    const std::size_t nn = face ? fn : en;
    const std::uint32_t* want = face ? &m.faces[c * fn] : &m.edges[(c - nf) * en];
    ASSERT_EQ(std::size_t(pts->GetNumberOfIds()), nn) << "cell " << c;
    for (std::size_t i = 0; i < nn; ++i)
      EXPECT_EQ(ids[std::size_t(pts->GetId(vtkIdType(i)))], want[i]) << "cell " << c;
  }

  // dim and entity.
  vtkDataArray* dim = grid->GetCellData()->GetArray("dim");
  vtkDataArray* entity = grid->GetCellData()->GetArray("entity");
  ASSERT_NE(dim, nullptr);
  ASSERT_NE(entity, nullptr);
  EXPECT_EQ(dim->GetDataTypeSize(), 1);
  EXPECT_EQ(entity->GetDataType(), VTK_UNSIGNED_INT);
  for (std::size_t c = 0; c < nf + ne; ++c) {
    EXPECT_EQ(dim->GetTuple1(vtkIdType(c)), c < nf ? 2 : 1) << "cell " << c;
    EXPECT_EQ(entity->GetTuple1(vtkIdType(c)), c < nf ? m.face_entity[c] : m.edge_entity[c - nf])
        << "cell " << c;
  }

  // One 0/1 array per group of dim 1 or 2, named as the header says, plus {tag, dim} field data.
  std::size_t written = 0;
  for (std::size_t g = 0; g < m.groups.size(); ++g) {
    const FeGroup& grp = m.groups[g];
    if (grp.dim == 3) continue;
    ++written;
    bool clash = grp.name == "dim" || grp.name == "entity";
    for (const FeGroup& o : m.groups)
      if (o.dim != 3 && o.dim != grp.dim && o.name == grp.name) clash = true;
    const std::string name = clash ? grp.name + ".d" + std::to_string(grp.dim) : grp.name;
    vtkDataArray* a = grid->GetCellData()->GetArray(name.c_str());
    ASSERT_NE(a, nullptr) << name;
    EXPECT_EQ(a->GetDataTypeSize(), 1) << name;
    std::size_t members = 0;
    for (std::size_t c = 0; c < nf + ne; ++c) {
      const int cdim = c < nf ? 2 : 1;
      const std::uint32_t e = c < nf ? m.face_entity[c] : m.edge_entity[c - nf];
      const bool in = cdim == grp.dim && lists(grp, e);
      members += in;
      EXPECT_EQ(a->GetTuple1(vtkIdType(c)), in ? 1 : 0) << name << " cell " << c;
    }
    EXPECT_GT(members, 0u) << name;
    vtkDataArray* tag = grid->GetFieldData()->GetArray(name.c_str());
    ASSERT_NE(tag, nullptr) << name;
    ASSERT_EQ(tag->GetNumberOfTuples(), 2) << name;
    EXPECT_EQ(tag->GetTuple1(0), double(g + 1)) << name;
    EXPECT_EQ(tag->GetTuple1(1), grp.dim) << name;
  }
  EXPECT_EQ(std::size_t(grid->GetCellData()->GetNumberOfArrays()), 2 + written);
  EXPECT_EQ(std::size_t(grid->GetFieldData()->GetNumberOfArrays()), written);
}

TEST(BoundaryVtu, LinearCubeReadsBackWithEveryArray) {
  const FeMesh m = cube(2, 1);
  ASSERT_EQ(m.num_faces(), 6u * 8u);  // 2 x 2 squares per side, 2 triangles each
  ASSERT_EQ(m.num_edges(), 12u * 2u);
  const std::string path = scratch(".vtu");
  write_boundary_vtu(m, path);
  const auto grid = read_back(path);
  expect_boundary_of(m, grid);
  EXPECT_EQ(grid->GetNumberOfPoints(), 26);  // the 27 grid points but the centre
  // The clash rule of the header: "load" exists in dims 1 and 2; "entity" is reserved.
  for (const char* name : {"load.d1", "load.d2", "entity.d2", "xmin", "walls", "corner_edges"})
    EXPECT_NE(grid->GetCellData()->GetArray(name), nullptr) << name;
  EXPECT_EQ(grid->GetCellData()->GetArray("load"), nullptr);
  EXPECT_EQ(grid->GetCellData()->GetArray("solid"), nullptr);
  EXPECT_TRUE(leftover_temps(path).empty());
}

TEST(BoundaryVtu, FacesKeepTheirOutwardOrientation) {
  // VTK's own normal of every triangle cell points away from the cube's centre.
  const FeMesh m = cube(2, 1);
  const std::string path = scratch(".vtu");
  write_boundary_vtu(m, path);
  const auto grid = read_back(path);
  for (vtkIdType c = 0; c < vtkIdType(m.num_faces()); ++c) {
    double p[3][3];
    for (int i = 0; i < 3; ++i) grid->GetCell(c)->GetPoints()->GetPoint(i, p[i]);
    const double centre[3] = {0.5, 0.5, 0.5};
    EXPECT_GT(test::det3(centre, p[0], p[1], p[2]), 0) << "face " << c;  // centre below the face
  }
}

TEST(BoundaryVtu, QuadraticCellsHaveVtkNodeOrder) {
  const FeMesh m = cube(2, 2);
  const std::string path = scratch(".vtu");
  write_boundary_vtu(m, path);
  const auto grid = read_back(path);
  expect_boundary_of(m, grid);
  // 26 corners + the mid-nodes of the boundary edges: per side 2 x 2 squares have 12 grid
  // edges and 4 diagonals, 16 per side; the 12 cube edges (2 segments each) are shared by 2
  // sides: 6 * 16 - 24 = 72.
  EXPECT_EQ(grid->GetNumberOfPoints(), 26 + 72);
  // VTK's own edges of each cell (vtkCell::GetEdge: ends, then the mid-node) must have their
  // mid-node at their midpoint: the test mesh puts every mid-node there, so a node-order
  // mismatch between FeMesh and VTK would show here.
  int checked = 0;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c) {
    vtkCell* cell = grid->GetCell(c);
    const int edges = cell->GetCellType() == VTK_QUADRATIC_TRIANGLE ? 3 : 1;
    for (int k = 0; k < edges; ++k) {
      vtkCell* e = cell->GetCellType() == VTK_QUADRATIC_TRIANGLE ? cell->GetEdge(k) : cell;
      ASSERT_EQ(e->GetNumberOfPoints(), 3);
      double a[3], b[3], mid[3];
      e->GetPoints()->GetPoint(0, a);
      e->GetPoints()->GetPoint(1, b);
      e->GetPoints()->GetPoint(2, mid);
      for (int i = 0; i < 3; ++i) EXPECT_EQ(mid[i], (a[i] + b[i]) / 2) << "cell " << c << " edge " << k;
      ++checked;
    }
  }
  EXPECT_EQ(checked, int(3 * m.num_faces() + m.num_edges()));
}

TEST(BoundaryVtu, FacesOnlyAndEdgesOnly) {
  FeMesh faces_only = cube(2, 1);
  faces_only.edges.clear();
  faces_only.edge_entity.clear();
  faces_only.groups.erase(std::remove_if(faces_only.groups.begin(), faces_only.groups.end(),
                                         [](const FeGroup& g) { return g.dim == 1; }),
                          faces_only.groups.end());
  std::string path = scratch(".vtu");
  write_boundary_vtu(faces_only, path);
  expect_boundary_of(faces_only, read_back(path));
  // Without the dim-1 "load", the dim-2 one keeps its plain name.
  EXPECT_NE(read_back(path)->GetCellData()->GetArray("load"), nullptr);

  FeMesh edges_only = cube(2, 1);
  edges_only.faces.clear();
  edges_only.face_entity.clear();
  edges_only.groups.erase(std::remove_if(edges_only.groups.begin(), edges_only.groups.end(),
                                         [](const FeGroup& g) { return g.dim == 2; }),
                          edges_only.groups.end());
  path = scratch(".vtu");
  write_boundary_vtu(edges_only, path);
  const auto grid = read_back(path);
  expect_boundary_of(edges_only, grid);
  EXPECT_EQ(grid->GetNumberOfPoints(), 8 + 12);  // corners and the edges' middle grid points
}

/// `write` must throw E whose message contains `part`, leave an existing file at the path
/// untouched and no temporary beside it.
template <class E>
void expect_failure(const FeMesh& m, const std::string& part) {
  const std::string path = scratch(".vtu");
  {
    std::ofstream(path) << "previous";
  }
  try {
    write_boundary_vtu(m, path);
    ADD_FAILURE() << "no error; expected '" << part << "'";
  } catch (const E& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("write_boundary_vtu"), std::string::npos) << e.what();
  }
  EXPECT_EQ(slurp(path), "previous");
  EXPECT_TRUE(leftover_temps(path).empty());
}

TEST(BoundaryVtu, InvalidMeshThrowsUsageErrorAndWritesNothing) {
  {
    FeMesh m = cube(2, 1);
    m.faces[7] = std::uint32_t(m.points.size());
    expect_failure<UsageError>(m, "face 2 references point 27");
  }
  {
    FeMesh m = cube(2, 2);
    m.edges.pop_back();
    expect_failure<UsageError>(m, "not a multiple of 3");
  }
  {
    FeMesh m = cube(2, 1);
    m.face_entity.pop_back();
    expect_failure<UsageError>(m, "face_entity has 47 values for 48 faces");
  }
  {
    FeMesh m = cube(2, 1);
    m.groups.push_back({"nowhere", 2, {99}});
    expect_failure<UsageError>(m, "lists entity 99");
  }
  {
    FeMesh m = cube(2, 1);
    m.groups.push_back({"bad name", 1, {kCurve0}});
    expect_failure<UsageError>(m, "outside [A-Za-z0-9_-]");
  }
  {
    FeMesh m = cube(2, 1);
    m.points.xyz[5] = NAN;
    expect_failure<UsageError>(m, "point 1 has a non-finite coordinate");
  }
  {
    FeMesh m = cube(2, 1);
    m.faces.clear();
    m.face_entity.clear();
    m.edges.clear();
    m.edge_entity.clear();
    m.groups.resize(1);  // "solid" only
    expect_failure<UsageError>(m, "no boundary faces and no feature edges");
  }
}

TEST(BoundaryVtu, MissingDirectoryThrowsOutputError) {
  const std::string path = scratch("-nodir") + "/sub/boundary.vtu";
  try {
    write_boundary_vtu(cube(2, 1), path);
    ADD_FAILURE() << "no OutputError";
  } catch (const OutputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(path));
}

}  // namespace
}  // namespace kdmesh
