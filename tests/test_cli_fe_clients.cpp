// kdmesh — the solver outputs of `kdmesh batch` read by the real clients (gmsh, meshio).
// SPDX-License-Identifier: AGPL-3.0-or-later
// Two jobs on the shipped block (models/block/block.stl) at a coarse size: linear with MSH 4.1
// and quadratic with MSH 2.2, each also writing the volume VTU, INP, MEDIT and boundary VTU.
// Gmsh's own statistics (nodes, tets, triangles, min Jacobian) and its re-saved file, and
// meshio's reading of every file, must agree with the job's summary JSON. A missing client
// skips (or fails with KDMESH_REQUIRE_CLIENTS=1).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/fe_mesh.h"
#include "io/msh_reader.h"
#include "io/surface_io.h"
#include "mesher/fe/fe_assembly.h"
#include "tests/support/box_surface.h"
#include "tests/support/clients.h"
#include "tests/support/run_cli.h"

namespace kdmesh {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using test::have_command;
using test::have_meshio;
using test::ToolRun;

fs::path tmpdir() { return test::process_tmpdir("cli_fe_clients"); }

/// The batch file: both jobs share the block, its three refined edges (zone and group
/// `fixed_edges`, dim 1) and the top face as `load` (dim 2). The linear job also has `skin`,
/// every face, and patch_groups (patch_<i>, curve_<i>), so the top faces are in three groups:
/// fine in MSH 4.1 and the boundary VTU; the quadratic one has neither, since MSH 2.2 would
/// repeat such faces (io/msh_writer.h). patch_groups also gives every entity a physical group,
/// which meshio 5.0 needs to read MSH 4.1 at all: it fails on files where only some entities
/// have one ("Incompatible cell data 'gmsh:physical'", meshio issue #1388), Gmsh's own -save_all
/// output included.
fs::path write_batch() {
  const fs::path yaml = tmpdir() / "fe-clients.yaml";
  const std::string stl = std::string(KDMESH_SOURCE_DIR) + "/models/block/block.stl";
  std::ofstream(yaml) << "defaults:\n"
                         "  input: " + stl + "\n" + R"(  size: 20
  gradation: 0.2
  sharp_angle: 30
  seed: 1
  zones:
    - {type: polyline, name: fixed_edges, size: 4, points: [[0, 0, 0], [100, 0, 0]]}
    - {type: polyline, name: fixed_edges, size: 4, points: [[100, 0, 100], [100, 100, 100]]}
    - {type: polyline, name: fixed_edges, size: 4, points: [[0, 100, 0], [0, 100, 100]]}
  groups:
    - {name: fixed_edges, zone: fixed_edges}
    - {name: load, point: [50, 50, 100]}
jobs:
  - name: linear
    element_order: 1
    msh_version: 4.1
    patch_groups: true
    groups:
      - {name: fixed_edges, zone: fixed_edges}
      - {name: load, point: [50, 50, 100]}
      - {name: skin, box: {min: [-1, -1, -1], max: [101, 101, 101]}}
    output: {vtu: linear.vtu, summary: linear.json, msh: linear.msh, inp: linear.inp,
             mesh: linear.mesh, boundary_vtu: linear-boundary.vtu}
  - name: quadratic
    element_order: 2
    msh_version: 2.2
    output: {vtu: quadratic.vtu, summary: quadratic.json, msh: quadratic.msh, inp: quadratic.inp,
             mesh: quadratic.mesh, boundary_vtu: quadratic-boundary.vtu}
)";
  return yaml;
}

struct JobRun {
  fs::path dir;  ///< the batch's --out-dir
  json summary;  ///< the job's summary file
  std::string file(const std::string& key) const { return summary["outputs"].value(key, std::string()); }
};

/// Runs one job of the batch (once per process: ctest runs every test case as a process).
const JobRun& run_job(const std::string& name) {
  static std::map<std::string, JobRun> runs;
  if (const auto it = runs.find(name); it != runs.end()) return it->second;
  JobRun run;
  run.dir = tmpdir() / ("out-" + name);
  const test::CliResult r = test::run_kdmesh("batch " + write_batch().string() + " --only " + name +
                                                 " --out-dir " + run.dir.string() + " -q",
                                             tmpdir());
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  std::ifstream in(run.dir / (name + ".json"));
  if (in) run.summary = json::parse(in, nullptr, false);
  if (!run.summary.is_object()) run.summary = json::object();
  return runs.emplace(name, std::move(run)).first->second;
}

/// The summary's figures the files are checked against.
struct Expected {
  long nodes = 0;       ///< FE nodes: the mesh nodes, plus the mid-edge nodes for order 2
  long tets = 0, faces = 0, edges = 0;
  long patches = 0, curves = 0;
  double volume = 0;    ///< mesh_check.mesh_volume (the linear tets)
  struct Group {
    std::string name;
    int dim;
    long entities, elements;
  };
  std::vector<Group> groups;  ///< in physical-tag order (tag = position + 1)
};

Expected expected_from(const JobRun& run, int order) {
  const json& s = run.summary;
  Expected e;
  EXPECT_EQ(s.value("status", std::string()), "ok");
  if (!s.contains("counts") || !s.contains("groups") || !s.contains("mesh_check")) {
    ADD_FAILURE() << "summary without counts / groups / mesh_check: " << s.dump(1);
    return e;
  }
  const json& c = s["counts"];
  e.nodes = c["nodes"].get<long>();
  if (order == 2) e.nodes += s["quadratic"]["mid_nodes"].get<long>();
  e.tets = c["tets"].get<long>();
  e.faces = c["boundary_faces"].get<long>();
  e.edges = c["mesh_feature_edges"].get<long>();
  e.patches = c["patches"].get<long>() - s["boundary"]["empty_patches"].get<long>();
  e.curves = c["curves"].get<long>() - s["boundary"]["empty_curves"].get<long>();
  e.volume = s["mesh_check"]["mesh_volume"].get<double>();
  for (const json& g : s["groups"])
    e.groups.push_back({g["name"].get<std::string>(), g["dim"].get<int>(), g["entities"].get<long>(),
                        g["elements"].get<long>()});
  // The block: one body, 6 faces, 12 edges; all files are checked against these figures, so
  // they must be plausible themselves.
  EXPECT_EQ(c["bodies"].get<long>(), 1);
  EXPECT_EQ(e.patches, 6);
  EXPECT_EQ(e.curves, 12);
  EXPECT_GT(e.tets, 100);
  EXPECT_NEAR(e.volume, s["solid_volume"].get<double>(), 1e-9 * e.volume);
  for (const char* key : {"vtu", "summary", "msh", "inp", "medit", "boundary_vtu"})
    EXPECT_TRUE(fs::exists(run.file(key))) << key << ": " << run.file(key);
  return e;
}

const Expected::Group* find_group(const Expected& e, const std::string& name, int dim) {
  for (const auto& g : e.groups)
    if (g.name == name && g.dim == dim) return &g;
  return nullptr;
}

// =============================================================================================
// gmsh
// =============================================================================================

/// Gmsh's own view of a mesh file: its statistics after Merge, and the AnalyseMeshQuality
/// plugin's minimum Jacobian determinant over the tets.
struct GmshStats {
  long nodes = -1, tets = -1, triangles = -1;
  double min_j = NAN;
};

GmshStats gmsh_stats(const std::string& file) {
  const std::string geo = file + ".stats.geo";
  test::write_text_file(geo, "Merge \"" + file + "\";\n"
                             "Printf(\"kdmesh-stat nodes %.0f\", Mesh.NbNodes);\n"
                             "Printf(\"kdmesh-stat tets %.0f\", Mesh.NbTetrahedra);\n"
                             "Printf(\"kdmesh-stat triangles %.0f\", Mesh.NbTriangles);\n"
                             "Plugin(AnalyseMeshQuality).JacobianDeterminant = 1;\n"
                             "Plugin(AnalyseMeshQuality).DimensionOfElements = 3;\n"
                             "Plugin(AnalyseMeshQuality).CreateView = 0;\n"
                             "Plugin(AnalyseMeshQuality).Run;\n");
  const ToolRun r = test::run_tool("gmsh " + geo + " -parse_and_exit", geo);
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.find("Error"), std::string::npos) << r.out;
  GmshStats s;
  for (const std::string& line : test::text_lines(r.out)) {
    std::istringstream in(line);
    std::string word, key;
    double v = 0;
    if (line.rfind("kdmesh-stat ", 0) == 0 && (in >> word >> key >> v)) {
      (key == "nodes" ? s.nodes : key == "tets" ? s.tets : s.triangles) = long(v);
      continue;
    }
    // "Info    : minJ/maxJ = ..." (the worst ratio) and "Info    : minJ = min, avg, max".
    const auto eq = line.find('=');
    if (eq != std::string::npos && line.find("minJ ") != std::string::npos &&
        line.find("minJ/maxJ") == std::string::npos)
      s.min_j = std::stod(line.substr(eq + 1));
  }
  return s;
}

/// Gmsh opens `msh` and saves every element again as MSH 4.1; read back, it must hold the
/// summary's nodes, tets, faces, feature edges, groups (entities and elements per physical
/// group) and volume.
void check_gmsh_resave(const std::string& msh, const Expected& e, int order) {
  const std::string out = msh + ".gmsh41.msh";
  const ToolRun r = test::run_tool("gmsh " + msh + " -save -save_all -format msh41 -o " + out, out);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.find("Error"), std::string::npos) << r.out;
  const FeMesh back = read_msh(out);
  EXPECT_EQ(back.order, order);
  EXPECT_EQ(long(back.points.size()), e.nodes);
  EXPECT_EQ(long(back.num_tets()), e.tets);
  EXPECT_EQ(long(back.num_faces()), e.faces);
  EXPECT_EQ(long(back.num_edges()), e.edges);
  ASSERT_EQ(back.groups.size(), e.groups.size());
  for (std::size_t g = 0; g < back.groups.size(); ++g) {
    const FeGroup& grp = back.groups[g];
    EXPECT_EQ(grp.name, e.groups[g].name);
    EXPECT_EQ(grp.dim, e.groups[g].dim) << grp.name;
    EXPECT_EQ(long(grp.entities.size()), e.groups[g].entities) << grp.name;
    const auto& of = grp.dim == 3 ? back.tet_entity : grp.dim == 2 ? back.face_entity : back.edge_entity;
    long elements = 0;
    for (const std::uint32_t x : of)
      elements += std::count(grp.entities.begin(), grp.entities.end(), x) > 0;
    EXPECT_EQ(elements, e.groups[g].elements) << grp.name;
  }
  // The block's faces are planar and its edges straight, so curved order-2 elements enclose the
  // same volume as the linear ones.
  EXPECT_NEAR(fe_mesh_volume(back), e.volume, 1e-9 * e.volume);
}

void check_gmsh_stats(const std::string& file, const Expected& e, long triangles) {
  SCOPED_TRACE(file);
  const GmshStats s = gmsh_stats(file);
  EXPECT_EQ(s.nodes, e.nodes);
  EXPECT_EQ(s.tets, e.tets);
  EXPECT_EQ(s.triangles, triangles);
  EXPECT_GT(s.min_j, 0);
}

TEST(FeClients, GmshAgreesWithTheLinearJob) {
  KDMESH_NEED_CLIENT(have_command("gmsh"), "gmsh");
  const JobRun& run = run_job("linear");
  const Expected e = expected_from(run, 1);
  ASSERT_FALSE(HasFailure());
  check_gmsh_stats(run.file("msh"), e, e.faces);
  check_gmsh_stats(run.file("medit"), e, e.faces);
  check_gmsh_resave(run.file("msh"), e, 1);
}

TEST(FeClients, GmshAgreesWithTheQuadraticJob) {
  KDMESH_NEED_CLIENT(have_command("gmsh"), "gmsh");
  const JobRun& run = run_job("quadratic");
  const Expected e = expected_from(run, 2);
  ASSERT_FALSE(HasFailure());
  // MSH 2.2 writes a face once per group listing its patch, at least once: `load` is the only
  // face group here, so every face once.
  check_gmsh_stats(run.file("msh"), e, e.faces);
  check_gmsh_stats(run.file("medit"), e, e.faces);
  check_gmsh_resave(run.file("msh"), e, 2);
}

// Two touching bodies (issue 21): Gmsh reads the assembly's MSH 4.1 and MEDIT files with the
// nodes, tets and triangles of the summary (the boundary faces and, once each, the faces of the
// interface between the bodies), and saved again by Gmsh, the physical groups: both volumes,
// both exteriors and the interface, with their elements.
TEST(FeClients, GmshAgreesWithAnAssemblyOfTwoTouchingBodies) {
  KDMESH_NEED_CLIENT(have_command("gmsh"), "gmsh");
  const fs::path dir = tmpdir() / "assembly";
  fs::create_directories(dir);
  write_stl(test::box_surface({0, 0, 0}, {1, 1, 1}), (dir / "first.stl").string());
  write_stl(test::box_surface({1, 0, 0}, {2, 1, 1}), (dir / "second.stl").string());
  test::write_text_file((dir / "pair.yaml").string(),
                        "jobs:\n  - name: pair\n    bodies: [{name: first, input: first.stl}, {name: second, input: second.stl}]\n"
                        "    size: 0.25\n    output: {summary: pair.json, msh: pair.msh, mesh: pair.mesh}\n");
  const test::CliResult r = test::run_kdmesh("batch " + (dir / "pair.yaml").string() + " -q --out-dir " + dir.string(), dir);
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  std::ifstream in(dir / "pair.json");
  const json s = json::parse(in);
  Expected e;
  e.nodes = s["counts"]["nodes"].get<long>();
  e.tets = s["counts"]["tets"].get<long>();
  const long interface_faces = s["mesh_check"]["interface_faces"].get<long>();
  EXPECT_GT(interface_faces, 0);
  e.faces = s["counts"]["boundary_faces"].get<long>() + interface_faces;
  e.edges = 0;  // no curve group: MSH 4.1 keeps the entities of some group only
  e.volume = s["mesh_check"]["mesh_volume"].get<double>();
  for (const json& g : s["groups"])
    e.groups.push_back({g["name"].get<std::string>(), g["dim"].get<int>(), g["entities"].get<long>(),
                        g["elements"].get<long>()});
  const Expected::Group* between = find_group(e, "first-second", 2);
  ASSERT_NE(between, nullptr);
  EXPECT_EQ(between->elements, interface_faces);
  for (const char* name : {"first", "second"}) {
    EXPECT_NE(find_group(e, name, 3), nullptr) << name;
    EXPECT_NE(find_group(e, std::string(name) + "-exterior", 2), nullptr) << name;
  }
  check_gmsh_stats((dir / "pair.msh").string(), e, e.faces);
  check_gmsh_stats((dir / "pair.mesh").string(), e, e.faces);
  check_gmsh_resave((dir / "pair.msh").string(), e, 1);
}

// =============================================================================================
// meshio
// =============================================================================================

using View = std::map<std::string, std::vector<std::string>>;

/// meshio's reading of the files `tag:format:path`: "key values..." lines (see the script).
/// Cross-file checks in the script: the boundary VTU's faces and lines are those of the .msh,
/// compared by the coordinates of all their nodes in order (triangle6 and line3 have the same
/// node order in VTK and Gmsh, and both files start each element at the same corner).
View meshio_view(const std::vector<std::string>& files, const std::string& base) {
  const std::string script = base + ".meshio.py";
  test::write_text_file(script, R"PY(import sys
from collections import Counter
import numpy as np
import meshio

meshes = {}
for arg in sys.argv[1:]:
    tag, fmt, path = arg.split(":", 2)
    m = meshio.read(path, file_format=fmt)
    meshes[tag] = m
    print(tag + ".points", len(m.points))
    counts = Counter()
    for c in m.cells:
        counts[c.type] += len(c.data)
    for t in sorted(counts):
        print(tag + ".cells." + t, counts[t])
    vols = [np.einsum("ij,ij->i", P[:, 1] - P[:, 0], np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 0])) / 6
            for P in (m.points[c.data[:, :4]] for c in m.cells if c.type in ("tetra", "tetra10"))]
    if vols:
        v = np.concatenate(vols)
        print(tag + ".volume", repr(float(v.sum())))
        print(tag + ".nonpositive", int((v <= 0).sum()))
    for name in sorted(m.cell_sets):
        print(tag + ".cellset." + name.lower(), sum(len(x) for x in m.cell_sets[name]))
    for name in sorted(m.point_sets):
        print(tag + ".pointset." + name.lower(), len(m.point_sets[name]))
    for name in sorted(m.field_data):
        print(tag + ".field." + name, *[int(x) for x in np.ravel(m.field_data[name])])
    for name in sorted(m.cell_data):
        print(tag + ".celldata." + name, sum(len(x) for x in m.cell_data[name]))
    for name in sorted(m.point_data):
        print(tag + ".pointdata." + name, len(m.point_data[name]))

b = meshes.get("bvtu")
if b is not None:
    cat = lambda name: np.concatenate([np.ravel(x) for x in b.cell_data[name]])
    dims, ent = cat("dim"), cat("entity")
    print("bvtu.faces", int((dims == 2).sum()))
    print("bvtu.lines", int((dims == 1).sum()))
    print("bvtu.patches", len(set(ent[dims == 2].tolist())))
    print("bvtu.curves", len(set(ent[dims == 1].tolist())))
    nid = np.ravel(b.point_data["node_id"])
    print("bvtu.node_ids_distinct", int(len(set(nid.tolist())) == len(nid)))
    for name in sorted(b.field_data):
        print("bvtu.group." + name, int(cat(name).sum()))
        nodes = set()
        for c, member in zip(b.cells, b.cell_data[name]):
            nodes.update(nid[c.data[np.ravel(member) == 1].ravel()].tolist())
        print("bvtu.groupnodes." + name, len(nodes))

    def elements(m, types):
        out = Counter()
        for c in m.cells:
            if c.type in types:
                for row in m.points[c.data]:
                    out[tuple(map(tuple, row.tolist()))] += 1
        return out

    msh = meshes.get("msh")
    if msh is not None:
        faces, lines = ("triangle", "triangle6"), ("line", "line3")
        print("bvtu.faces_as_msh", int(elements(b, faces) == elements(msh, faces)))
        print("bvtu.lines_as_msh", int(elements(b, lines) == elements(msh, lines)))
)PY");
  std::string cmd = "/usr/bin/python3 " + script;
  for (const std::string& f : files) cmd += " " + f;
  const ToolRun r = test::run_tool(cmd, script);
  EXPECT_EQ(r.code, 0) << r.out;
  View view;
  for (const std::string& line : test::text_lines(r.out)) {
    std::istringstream in(line);
    std::string key, v;
    in >> key;
    while (in >> v) view[key].push_back(v);
  }
  return view;
}

long num(const View& v, const std::string& key) {
  const auto it = v.find(key);
  return it == v.end() || it->second.empty() ? -1 : std::stol(it->second[0]);
}

double real(const View& v, const std::string& key) {
  const auto it = v.find(key);
  return it == v.end() || it->second.empty() ? NAN : std::stod(it->second[0]);
}

/// Everything meshio reads from one job's files, against its summary.
void check_meshio(const JobRun& run, const Expected& e, int order) {
  const std::string tet = order == 2 ? "tetra10" : "tetra";
  const std::string tri = order == 2 ? "triangle6" : "triangle";
  const std::string line = order == 2 ? "line3" : "line";
  std::vector<std::string> files = {"vtu:vtu:" + run.file("vtu"), "bvtu:vtu:" + run.file("boundary_vtu"),
                                    "msh:gmsh:" + run.file("msh"), "inp:abaqus:" + run.file("inp")};
  if (order == 1) files.push_back("medit:medit:" + run.file("medit"));  // meshio 5 reads no P2 MEDIT
  const View v = meshio_view(files, (run.dir / "meshio").string());

  // Volume VTU: the linear mesh (its points are the mesh nodes, no mid-edge nodes).
  const long linear_nodes = run.summary["counts"]["nodes"].get<long>();
  EXPECT_EQ(num(v, "vtu.points"), linear_nodes);
  EXPECT_EQ(num(v, "vtu.cells.tetra"), e.tets);
  EXPECT_EQ(num(v, "vtu.nonpositive"), 0);
  EXPECT_NEAR(real(v, "vtu.volume"), e.volume, 1e-9 * e.volume);
  EXPECT_EQ(num(v, "vtu.celldata.region"), e.tets);
  EXPECT_EQ(num(v, "vtu.pointdata.node_kind"), linear_nodes);

  // Solver formats: nodes, elements by type, volume (from the corner nodes), groups.
  for (const std::string f : {"msh", "inp", "medit"}) {
    if (f == "medit" && order == 2) continue;
    SCOPED_TRACE(f);
    EXPECT_EQ(num(v, f + ".points"), e.nodes);
    EXPECT_EQ(num(v, f + ".cells." + tet), e.tets);
    EXPECT_EQ(num(v, f + ".nonpositive"), 0);
    EXPECT_NEAR(real(v, f + ".volume"), e.volume, 1e-9 * e.volume);
    if (f != "inp") {  // INP holds faces as *SURFACE (tet, face) pairs, not as elements
      EXPECT_EQ(num(v, f + ".cells." + tri), e.faces);
      EXPECT_EQ(num(v, f + ".cells." + line), e.edges);
    }
  }
  for (std::size_t g = 0; g < e.groups.size(); ++g) {
    const Expected::Group& grp = e.groups[g];
    SCOPED_TRACE(grp.name);
    // MSH: physical names with {tag, dim}; 4.1 physical groups are meshio cell sets.
    const auto field = v.find("msh.field." + grp.name);
    ASSERT_NE(field, v.end());
    EXPECT_EQ(field->second, (std::vector<std::string>{std::to_string(g + 1), std::to_string(grp.dim)}));
    if (order == 1) {
      EXPECT_EQ(num(v, "msh.cellset." + grp.name), grp.elements);
    }
    if (grp.dim == 3) {
      EXPECT_EQ(num(v, "inp.cellset." + grp.name), grp.elements);
      EXPECT_EQ(num(v, "inp.pointset." + grp.name), e.nodes);  // the one body holds every node
      EXPECT_EQ(num(v, "bvtu.group." + grp.name), -1);         // volume groups are not written
      continue;
    }
    // Boundary VTU: one 0/1 array per group selecting the group's elements, {tag, dim} field
    // data as the .msh; INP: the NSET of the group = the nodes of those elements.
    EXPECT_EQ(num(v, "bvtu.group." + grp.name), grp.elements);
    const auto bfield = v.find("bvtu.field." + grp.name);
    ASSERT_NE(bfield, v.end());
    EXPECT_EQ(bfield->second, field->second);
    EXPECT_GT(num(v, "bvtu.groupnodes." + grp.name), 0);
    EXPECT_EQ(num(v, "inp.pointset." + grp.name), num(v, "bvtu.groupnodes." + grp.name));
  }
  EXPECT_EQ(num(v, "inp.cellset.eall"), e.tets);

  // Boundary VTU: every face and feature edge, with their patches and curves, and the very
  // elements of the .msh.
  EXPECT_EQ(num(v, "bvtu.cells." + tri), e.faces);
  EXPECT_EQ(num(v, "bvtu.cells." + line), e.edges);
  EXPECT_EQ(num(v, "bvtu.faces"), e.faces);
  EXPECT_EQ(num(v, "bvtu.lines"), e.edges);
  EXPECT_EQ(num(v, "bvtu.patches"), e.patches);
  EXPECT_EQ(num(v, "bvtu.curves"), e.curves);
  EXPECT_EQ(num(v, "bvtu.celldata.entity"), e.faces + e.edges);
  EXPECT_EQ(num(v, "bvtu.node_ids_distinct"), 1);
  EXPECT_GT(num(v, "bvtu.points"), 0);
  EXPECT_LT(num(v, "bvtu.points"), e.nodes);  // boundary nodes only
  EXPECT_EQ(num(v, "bvtu.faces_as_msh"), 1);
  EXPECT_EQ(num(v, "bvtu.lines_as_msh"), 1);
}

TEST(FeClients, MeshioReadsEveryFileOfTheLinearJob) {
  KDMESH_NEED_CLIENT(have_meshio(), "meshio (python3-meshio)");
  const JobRun& run = run_job("linear");
  const Expected e = expected_from(run, 1);
  ASSERT_FALSE(HasFailure());
  // The overlaps the boundary VTU must represent: the top face is in `load`, `skin` and its
  // patch_<i>; every face in `skin` and one patch_<i>; every feature edge in one curve_<i>.
  const Expected::Group* load = find_group(e, "load", 2);
  const Expected::Group* skin = find_group(e, "skin", 2);
  ASSERT_TRUE(load && skin);
  EXPECT_EQ(load->entities, 1);
  EXPECT_EQ(skin->entities, 6);
  EXPECT_EQ(skin->elements, e.faces);
  EXPECT_GT(load->elements, 0);
  long in_patches = 0, in_curves = 0, patch_groups = 0, curve_groups = 0;
  for (const Expected::Group& g : e.groups) {
    if (g.name.rfind("patch_", 0) == 0) in_patches += g.elements, ++patch_groups;
    if (g.name.rfind("curve_", 0) == 0) in_curves += g.elements, ++curve_groups;
  }
  EXPECT_EQ(patch_groups, e.patches);
  EXPECT_EQ(curve_groups, e.curves);
  EXPECT_EQ(in_patches, e.faces);
  EXPECT_EQ(in_curves, e.edges);
  check_meshio(run, e, 1);
}

TEST(FeClients, MeshioReadsEveryFileOfTheQuadraticJob) {
  KDMESH_NEED_CLIENT(have_meshio(), "meshio (python3-meshio)");
  const JobRun& run = run_job("quadratic");
  const Expected e = expected_from(run, 2);
  ASSERT_FALSE(HasFailure());
  check_meshio(run, e, 2);
}

}  // namespace
}  // namespace kdmesh
