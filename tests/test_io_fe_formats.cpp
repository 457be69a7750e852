// kdmesh — tests of the solver-format writers (Gmsh MSH, Abaqus/CalculiX INP, MEDIT) and their
// readers: round trips, the on-disk conventions checked against the formats' documentation,
// robustness of the readers, and real clients (gmsh, meshio, ccx) when they are installed.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/fe_mesh.h"
#include "io/inp_writer.h"
#include "io/medit_reader.h"
#include "io/medit_writer.h"
#include "io/msh_reader.h"
#include "io/msh_writer.h"
#include "tests/support/clients.h"
#include "tests/support/fe_cube.h"
#include "tests/support/scratch.h"

namespace kdmesh {
namespace {

namespace fs = std::filesystem;

using namespace test;  // the cube fixture (tests/support/fe_cube.h)

// =============================================================================================
// Checks
// =============================================================================================

double tet_volume(const FeMesh& m, std::size_t t) {
  const std::uint32_t* c = &m.tets[t * std::size_t(m.tet_nodes())];
  return det3(m.points.p(c[0]), m.points.p(c[1]), m.points.p(c[2]), m.points.p(c[3])) / 6;
}

/// Mid-edge nodes (FeMesh order) not at the midpoint of their corners, within `tol`.
int misplaced_midnodes(const FeMesh& m, double tol = 0) {
  if (m.order != 2) return 0;
  static const int kTetEdges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  static const int kTriEdges[3][2] = {{0, 1}, {1, 2}, {2, 0}};
  int bad = 0;
  auto check = [&](std::uint32_t mid, std::uint32_t a, std::uint32_t b) {
    for (int c = 0; c < 3; ++c)
      if (std::abs(m.points.p(mid)[c] - (m.points.p(a)[c] + m.points.p(b)[c]) / 2) > tol) {
        ++bad;
        return;
      }
  };
  for (std::size_t t = 0; t < m.num_tets(); ++t)
    for (int e = 0; e < 6; ++e) {
      const std::uint32_t* c = &m.tets[10 * t];
      check(c[4 + e], c[kTetEdges[e][0]], c[kTetEdges[e][1]]);
    }
  for (std::size_t f = 0; f < m.num_faces(); ++f)
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t* c = &m.faces[6 * f];
      check(c[3 + e], c[kTriEdges[e][0]], c[kTriEdges[e][1]]);
    }
  for (std::size_t e = 0; e < m.num_edges(); ++e) {
    const std::uint32_t* c = &m.edges[3 * e];
    check(c[2], c[0], c[1]);
  }
  return bad;
}

std::vector<std::uint32_t> sorted(std::vector<std::uint32_t> v) {
  std::sort(v.begin(), v.end());
  return v;
}

/// Exact equality of everything a round trip must keep (group entities compared as sets).
void expect_same_mesh(const FeMesh& a, const FeMesh& b) {
  EXPECT_EQ(a.order, b.order);
  ASSERT_EQ(a.points.size(), b.points.size());
  EXPECT_TRUE(a.points.xyz == b.points.xyz) << "coordinates differ";
  EXPECT_EQ(a.tets, b.tets);
  EXPECT_EQ(a.tet_entity, b.tet_entity);
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_EQ(a.face_entity, b.face_entity);
  EXPECT_EQ(a.edges, b.edges);
  EXPECT_EQ(a.edge_entity, b.edge_entity);
  ASSERT_EQ(a.groups.size(), b.groups.size());
  for (std::size_t g = 0; g < a.groups.size(); ++g) {
    EXPECT_EQ(a.groups[g].name, b.groups[g].name);
    EXPECT_EQ(a.groups[g].dim, b.groups[g].dim);
    EXPECT_EQ(sorted(a.groups[g].entities), sorted(b.groups[g].entities)) << a.groups[g].name;
  }
}

using test::have_command;
using test::have_meshio;
using test::ToolRun;

std::string slurp(const std::string& path) { return test::read_text(path); }
void spit(const std::string& path, const std::string& bytes) { test::write_text_file(path, bytes); }
std::vector<std::string> lines_of(const std::string& text) { return test::text_lines(text); }
ToolRun run(const std::string& cmd, const std::string& log_base) { return test::run_tool(cmd, log_base); }

std::string scratch(const std::string& ext) { return test::scratch_path("io_fe_formats", ext); }

// =============================================================================================
// Round trips through kdmesh's own readers
// =============================================================================================

TEST(MshFormat, RoundTripAllVersionsEncodingsAndOrders) {
  for (const int order : {1, 2})
    for (const int version : {41, 22})
      for (const bool binary : {false, true}) {
        SCOPED_TRACE("order " + std::to_string(order) + ", MSH " + std::to_string(version) +
                     (binary ? " binary" : " ascii"));
        const FeMesh mesh = cube_mesh(2, order);
        const std::string path = scratch(".msh");
        write_msh(mesh, path, {version, binary});
        const FeMesh back = read_msh(path);
        expect_same_mesh(mesh, back);
        EXPECT_EQ(misplaced_midnodes(back), 0);
        double volume = 0;
        for (std::size_t t = 0; t < back.num_tets(); ++t) {
          EXPECT_GT(tet_volume(back, t), 0) << "tet " << t;
          volume += tet_volume(back, t);
        }
        EXPECT_DOUBLE_EQ(volume, 1.0);
      }
}

TEST(MeditFormat, RoundTripOrder1And2) {
  for (const int order : {1, 2}) {
    const FeMesh mesh = cube_mesh(2, order);
    const std::string path = scratch(".mesh");
    write_medit(mesh, path);
    const FeMesh back = read_medit(path);
    expect_same_mesh(mesh, back);
    EXPECT_EQ(misplaced_midnodes(back), 0);
  }
}

/// The cube mesh without the groups "xmin" and "sides": side entity kSide0 then belongs to no
/// group.
FeMesh cube_without_xmin_group(int order) {
  FeMesh m = cube_mesh(2, order);
  for (const char* name : {"xmin", "sides"}) {
    const auto it = std::find_if(m.groups.begin(), m.groups.end(), [&](const FeGroup& g) { return g.name == name; });
    EXPECT_NE(it, m.groups.end()) << name;
    if (it != m.groups.end()) m.groups.erase(it);
  }
  for (const FeGroup& g : m.groups)
    EXPECT_FALSE(g.dim == 2 && std::count(g.entities.begin(), g.entities.end(), kSide0)) << g.name;
  return m;
}

TEST(MshFormat, Msh41WritesOnlyGroupedEntitiesUnlessSaveAll) {
  const FeMesh mesh = cube_without_xmin_group(1);
  const auto xmin_faces = std::size_t(std::count(mesh.face_entity.begin(), mesh.face_entity.end(), kSide0));
  ASSERT_GT(xmin_faces, 0u);
  for (const bool binary : {false, true}) {
    const std::string path = scratch(".msh");
    write_msh(mesh, path, {41, binary});  // Gmsh's default: entities in no group are not saved
    const FeMesh grouped = read_msh(path);
    EXPECT_EQ(grouped.points.size(), mesh.points.size());
    EXPECT_EQ(grouped.num_tets(), mesh.num_tets());
    EXPECT_EQ(grouped.num_faces(), mesh.num_faces() - xmin_faces);
    EXPECT_EQ(std::count(grouped.face_entity.begin(), grouped.face_entity.end(), kSide0), 0);
    EXPECT_EQ(grouped.num_edges(), mesh.num_edges());
    MshOptions all{41, binary};
    all.save_all = true;
    write_msh(mesh, path, all);
    const FeMesh everything = read_msh(path);
    EXPECT_EQ(everything.num_faces(), mesh.num_faces());
    EXPECT_EQ(std::count(everything.face_entity.begin(), everything.face_entity.end(), kSide0),
              std::ptrdiff_t(xmin_faces));
  }
}

TEST(MshFormat, IrrationalCoordinatesRoundTripBitForBit) {
  FeMesh mesh = cube_mesh(2, 1);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> jitter(-1e-3, 1e-3);
  for (double& v : mesh.points.xyz) v = v * 3.14159 + jitter(rng) * 1e-200 + jitter(rng);
  for (const MshOptions o : {MshOptions{41, false}, MshOptions{22, false}, MshOptions{41, true}}) {
    const std::string path = scratch(".msh");
    write_msh(mesh, path, o);
    EXPECT_TRUE(read_msh(path).points.xyz == mesh.points.xyz);
  }
  const std::string path = scratch(".mesh");
  write_medit(mesh, path);
  EXPECT_TRUE(read_medit(path).points.xyz == mesh.points.xyz);
}

// =============================================================================================
// On-disk conventions, checked against the formats' documentation (not against the writers)
// =============================================================================================

/// Gmsh reference manual, "Node ordering", Tetrahedron10: nodes 4..9 are the midpoints of
/// edges (0,1) (1,2) (2,0) (3,0) (3,2) (3,1). Parses the MSH 2.2 ASCII text directly.
TEST(MshFormat, Tet10NodesOnDiskFollowGmshOrdering) {
  const FeMesh mesh = cube_mesh(2, 2);
  const std::string path = scratch(".msh");
  write_msh(mesh, path, {22, false});
  const auto lines = lines_of(slurp(path));
  std::map<long, std::array<double, 3>> xyz;
  std::size_t i = 0;
  while (lines[i] != "$Nodes") ++i;
  const long nn = std::stol(lines[++i]);
  for (long k = 0; k < nn; ++k) {
    std::istringstream in(lines[++i]);
    long tag;
    std::array<double, 3> p;
    in >> tag >> p[0] >> p[1] >> p[2];
    xyz[tag] = p;
  }
  while (lines[i] != "$Elements") ++i;
  const long ne = std::stol(lines[++i]);
  static const int kGmshEdge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}};
  int tet10 = 0;
  for (long k = 0; k < ne; ++k) {
    std::istringstream in(lines[++i]);
    long tag, type, ntags;
    in >> tag >> type >> ntags;
    for (long j = 0; j < ntags; ++j) in >> tag;
    if (type != 11) continue;
    long n[10];
    for (long& v : n) in >> v;
    ++tet10;
    for (int e = 0; e < 6; ++e)
      for (int c = 0; c < 3; ++c)
        ASSERT_EQ(xyz[n[4 + e]][c], (xyz[n[kGmshEdge[e][0]]][c] + xyz[n[kGmshEdge[e][1]]][c]) / 2)
            << "tet10 line " << lines[i] << ", node " << 4 + e;
  }
  // 48 tets, each written once per group of its entity: "solid" and, for the right half,
  // "right_half" too.
  EXPECT_EQ(tet10, 48 + 24);
}

/// The $PhysicalNames and $Entities sections of MSH 4.1, parsed directly: every group with
/// its dimension and tag, every entity's bounding box and physical tags.
TEST(MshFormat, Msh41EntitiesAndPhysicalNames) {
  const FeMesh mesh = cube_mesh(2, 1);
  const std::string path = scratch(".msh");
  write_msh(mesh, path, {41, false});
  const std::string text = slurp(path);
  for (std::size_t g = 0; g < mesh.groups.size(); ++g) {
    const std::string line = std::to_string(mesh.groups[g].dim) + " " + std::to_string(g + 1) +
                             " \"" + mesh.groups[g].name + "\"\n";
    EXPECT_NE(text.find(line), std::string::npos) << line;
  }
  std::istringstream in(text.substr(text.find("$Entities\n") + 10));
  std::size_t num[4];
  in >> num[0] >> num[1] >> num[2] >> num[3];
  EXPECT_EQ(num[0], 0u);
  EXPECT_EQ(num[1], 12u);  // cube edges
  EXPECT_EQ(num[2], 7u);   // six sides and the interface
  EXPECT_EQ(num[3], 2u);   // two volumes
  // The right volume (tag 8): x in [1/2, 1], in "solid" (tag 1) and "right_half" (tag 2).
  in.ignore(1 << 20, '\n');  // rest of the counts line
  for (std::size_t k = 0; k < num[1] + num[2]; ++k) in.ignore(1 << 20, '\n');
  std::string line;
  std::getline(in, line);
  std::getline(in, line);
  EXPECT_EQ(line, "8 0.5 0 0 1 1 1 2 1 2 0");
}

/// Abaqus / CalculiX manuals: faces of C3D4 / C3D10 by corner node (1-based): S1 (1,2,3),
/// S2 (1,4,2), S3 (2,4,3), S4 (3,4,1).
const int kAbaqusFaceCorners[4][3] = {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {2, 3, 0}};

/// What an .inp file says, parsed with the Abaqus keyword-line rules (continuation lines end
/// with a comma).
struct InpDeck {
  std::map<long, std::array<double, 3>> nodes;
  std::string element_type, node_nset;
  std::map<long, std::vector<long>> elements;
  std::map<std::string, std::vector<long>> elsets, nsets;
  std::map<std::string, std::vector<std::pair<long, int>>> surfaces;
  std::size_t longest_line = 0;
  std::size_t most_entries = 0;
};

std::string param(const std::string& keyword_line, const std::string& name) {
  const auto at = keyword_line.find(name + "=");
  if (at == std::string::npos) return "";
  const auto end = keyword_line.find(',', at);
  return keyword_line.substr(at + name.size() + 1,
                             end == std::string::npos ? std::string::npos : end - at - name.size() - 1);
}

InpDeck parse_inp(const std::string& path) {
  InpDeck deck;
  std::string block, kw;
  std::vector<std::string> pending;  // values of a data line with its continuations
  auto flush_record = [&] {
    if (pending.empty()) return;
    std::vector<std::string> v = pending;
    pending.clear();
    if (block == "*NODE") {
      deck.nodes[std::stol(v[0])] = {std::stod(v[1]), std::stod(v[2]), std::stod(v[3])};
    } else if (block == "*ELEMENT") {
      auto& e = deck.elements[std::stol(v[0])];
      for (std::size_t i = 1; i < v.size(); ++i) e.push_back(std::stol(v[i]));
    } else if (block == "*ELSET") {
      for (const auto& s : v) deck.elsets[param(kw, "ELSET")].push_back(std::stol(s));
    } else if (block == "*NSET") {
      for (const auto& s : v) deck.nsets[param(kw, "NSET")].push_back(std::stol(s));
    } else if (block == "*SURFACE") {
      EXPECT_EQ(v.size(), 2u);
      EXPECT_EQ(v[1].substr(0, 1), "S");
      deck.surfaces[param(kw, "NAME")].emplace_back(std::stol(v[0]), std::stoi(v[1].substr(1)));
    }
  };
  for (const std::string& line : lines_of(slurp(path))) {
    deck.longest_line = std::max(deck.longest_line, line.size());
    if (line.rfind("**", 0) == 0) continue;
    if (line.rfind("*", 0) == 0) {
      flush_record();
      kw = line;
      block = line.substr(0, line.find(','));
      if (block == "*ELEMENT") deck.element_type = param(line, "TYPE");
      if (block == "*NODE") deck.node_nset = param(line, "NSET");
      continue;
    }
    if (block == "*HEADING") continue;
    std::vector<std::string> fields;
    std::stringstream ss(line);
    for (std::string f; std::getline(ss, f, ',');) {
      f.erase(0, f.find_first_not_of(' '));
      if (!f.empty()) fields.push_back(f);
    }
    deck.most_entries = std::max(deck.most_entries, fields.size());
    pending.insert(pending.end(), fields.begin(), fields.end());
    // ELSET / NSET lists are one record per line; element lines ending with ',' continue.
    if (!(block == "*ELEMENT" && !line.empty() && line.back() == ',')) flush_record();
  }
  flush_record();
  return deck;
}

TEST(InpFormat, DeckMatchesMeshForBothOrders) {
  for (const int order : {1, 2}) {
    const FeMesh mesh = cube_mesh(2, order);
    const std::string path = scratch(".inp");
    write_inp(mesh, path);
    const InpDeck deck = parse_inp(path);
    EXPECT_LE(deck.longest_line, 80u);
    EXPECT_LE(deck.most_entries, 16u);
    EXPECT_EQ(deck.element_type, order == 2 ? "C3D10" : "C3D4");

    ASSERT_EQ(deck.nodes.size(), mesh.points.size());
    for (std::size_t n = 0; n < mesh.points.size(); ++n)
      for (int c = 0; c < 3; ++c) EXPECT_EQ(deck.nodes.at(long(n) + 1)[c], mesh.points.p(std::uint32_t(n))[c]);
    ASSERT_EQ(deck.elements.size(), mesh.num_tets());
    const int tn = mesh.tet_nodes();
    for (std::size_t t = 0; t < mesh.num_tets(); ++t) {
      const auto& e = deck.elements.at(long(t) + 1);
      ASSERT_EQ(e.size(), std::size_t(tn));
      for (int i = 0; i < tn; ++i) EXPECT_EQ(e[i], long(mesh.tets[t * tn + i]) + 1);
    }

    // ELSETs: every tet in EALL; "solid" all, "right_half" exactly the x > 1/2 tets.
    std::vector<long> all(mesh.num_tets()), right;
    for (std::size_t t = 0; t < mesh.num_tets(); ++t) {
      all[t] = long(t) + 1;
      if (mesh.tet_entity[t] == kRightVolume) right.push_back(long(t) + 1);
    }
    EXPECT_EQ(deck.elsets.at("solid"), all);
    EXPECT_EQ(deck.elsets.at("right_half"), right);
    EXPECT_EQ(deck.elsets.count("EALL"), 0u);  // EALL is the *ELEMENT line's ELSET
    EXPECT_EQ(deck.node_nset, "NALL");         // and NALL the *NODE line's NSET

    // NSETs: the nodes of each group's elements, ascending.
    for (const FeGroup& g : mesh.groups) {
      std::set<long> expect;
      const auto& conn = g.dim == 3 ? mesh.tets : g.dim == 2 ? mesh.faces : mesh.edges;
      const auto& ent = g.dim == 3 ? mesh.tet_entity : g.dim == 2 ? mesh.face_entity : mesh.edge_entity;
      const std::size_t nn = conn.size() / ent.size();
      for (std::size_t e = 0; e < ent.size(); ++e)
        if (std::count(g.entities.begin(), g.entities.end(), ent[e]))
          for (std::size_t i = 0; i < nn; ++i) expect.insert(long(conn[e * nn + i]) + 1);
      EXPECT_EQ(deck.nsets.at(g.name), std::vector<long>(expect.begin(), expect.end())) << g.name;
    }

    // SURFACEs: per face of the group one (element, Sk) whose Abaqus face has the face's
    // corners; the interface's faces belong to the tets they point out of (x < 1/2).
    for (const FeGroup& g : mesh.groups) {
      if (g.dim != 2) continue;
      const auto& entries = deck.surfaces.at(g.name);
      std::multiset<std::array<std::uint32_t, 3>> expect, got;
      for (std::size_t f = 0; f < mesh.num_faces(); ++f)
        if (std::count(g.entities.begin(), g.entities.end(), mesh.face_entity[f])) {
          const std::uint32_t* c = &mesh.faces[f * mesh.face_nodes()];
          expect.insert(sorted3(c[0], c[1], c[2]));
        }
      for (const auto& [el, label] : entries) {
        ASSERT_GE(label, 1);
        ASSERT_LE(label, 4);
        const auto& e = deck.elements.at(el);
        const int* fc = kAbaqusFaceCorners[label - 1];
        got.insert(sorted3(std::uint32_t(e[fc[0]] - 1), std::uint32_t(e[fc[1]] - 1),
                           std::uint32_t(e[fc[2]] - 1)));
        if (g.name == "interface") {
          EXPECT_EQ(mesh.tet_entity[std::size_t(el - 1)], kLeftVolume);
        }
      }
      EXPECT_EQ(got, expect) << g.name;
    }
  }
}

TEST(InpFormat, FaceLabelsAreTheManualsFaces) {
  const std::uint32_t tet[4] = {10, 11, 12, 13};
  for (int l = 0; l < 4; ++l) {
    const int* c = kAbaqusFaceCorners[l];
    EXPECT_EQ(abaqus_face_label(tet, tet[c[2]], tet[c[0]], tet[c[1]]), l + 1);
  }
  EXPECT_EQ(abaqus_face_label(tet, 10, 11, 99), 0);
}

TEST(InpFormat, LongCoordinatesFitCalculixFieldWidth) {
  FeMesh mesh = cube_mesh(2, 1);
  mesh.points.xyz[0] = -1.2345678901234567e-123;  // 24 characters in shortest form
  mesh.points.xyz[1] = 0.1;
  const std::string path = scratch(".inp");
  write_inp(mesh, path);
  const InpDeck deck = parse_inp(path);
  EXPECT_NEAR(deck.nodes.at(1)[0], mesh.points.xyz[0], 1e-12 * 1.3e-123);
  EXPECT_EQ(deck.nodes.at(1)[1], 0.1);
  for (const std::string& line : lines_of(slurp(path)))
    if (line.rfind("1, ", 0) == 0) {
      std::stringstream ss(line);
      std::string field;
      while (std::getline(ss, field, ',')) EXPECT_LE(field.size(), 21u) << line;  // ' ' + 20
      break;
    }
}

// =============================================================================================
// Errors
// =============================================================================================

template <class E, class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  ADD_FAILURE() << "no exception of the expected type";
  return "";
}

TEST(FeWriters, InvalidMeshesAreUsageErrorsAndLeaveNoFile) {
  const std::string path = scratch(".msh");
  FeMesh m = cube_mesh(2, 1);
  m.tets.push_back(0);
  EXPECT_NE(error_of<UsageError>([&] { write_msh(m, path); }).find("multiple of 4"), std::string::npos);
  m = cube_mesh(2, 1);
  m.faces[5] = 9999;
  EXPECT_NE(error_of<UsageError>([&] { write_medit(m, path); }).find("face 1 references point 9999"),
            std::string::npos);
  m = cube_mesh(2, 1);
  m.groups.push_back({"bad name", 2, {kSide0}});
  EXPECT_NE(error_of<UsageError>([&] { write_inp(m, path); }).find("outside [A-Za-z0-9_-]"),
            std::string::npos);
  m = cube_mesh(2, 1);
  m.groups.push_back({"ghost", 3, {42}});
  EXPECT_NE(error_of<UsageError>([&] { write_msh(m, path); }).find("entity 42, which has no tets"),
            std::string::npos);
  m = cube_mesh(2, 1);
  m.groups.push_back({"SOLID", 2, {kSide0}});  // same Abaqus name as the volume group "solid"
  EXPECT_NE(error_of<UsageError>([&] { write_inp(m, path); }).find("same Abaqus set name"),
            std::string::npos);
  m = cube_mesh(2, 1);
  m.groups.push_back({"nall", 2, {kSide0}});  // the all-nodes NSET of the *NODE line
  EXPECT_NE(error_of<UsageError>([&] { write_inp(m, path); }).find("all-nodes NSET 'NALL'"),
            std::string::npos);
  m = cube_mesh(2, 1);
  m.points.xyz[4] = std::nan("");
  EXPECT_NE(error_of<UsageError>([&] { write_msh(m, path); }).find("point 1 has a non-finite"),
            std::string::npos);
  EXPECT_NE(error_of<UsageError>([&] { write_msh(cube_mesh(2, 1), path, {40, false}); }).find("version 40"),
            std::string::npos);
  EXPECT_FALSE(fs::exists(path));
}

TEST(InpFormat, FaceOfNoTetIsNamed) {
  FeMesh m = cube_mesh(2, 1);
  // A triangle across the cube's interior that no tet has as a face.
  m.faces.insert(m.faces.end(), {0, 4, 26});
  m.face_entity.push_back(kSide0);
  const std::string path = scratch(".inp");
  const std::string msg = error_of<UsageError>([&] { write_inp(m, path); });
  EXPECT_NE(msg.find("face " + std::to_string(m.num_faces() - 1) + " (points 0 4 26, entity 20, group 'xmin')"),
            std::string::npos)
      << msg;
  EXPECT_FALSE(fs::exists(path));
}

// =============================================================================================
// Reader robustness: malformed input is an InputError with a location, never a crash
// =============================================================================================

void expect_input_error(const std::string& path, const std::string& bytes, bool msh,
                        const std::string& needle = "") {
  spit(path, bytes);
  try {
    msh ? read_msh(path) : read_medit(path);
    ADD_FAILURE() << "no InputError for:\n" << bytes.substr(0, 400);
  } catch (const InputError& e) {
    if (!needle.empty()) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  }
}

TEST(FeReaders, MalformedFilesAreInputErrorsWithLines) {
  const std::string p = scratch(".msh");
  const std::string head41 = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
  expect_input_error(p, "", true, "no $MeshFormat");
  expect_input_error(p, "$MeshFormat\n4.0 0 8\n$EndMeshFormat\n", true, ":2: MSH 4.0 is not supported");
  expect_input_error(p, head41 + "$Nodes\n1 2 1 2\n3 1 0 2\n1\n2\n0 0 0\n1 1 x\n$EndNodes\n", true,
                     ":10: a node coordinate: 'x' is not a number");
  expect_input_error(p, head41 + "$Nodes\n1 999999999 1 2\n", true, "exceeds what the remaining");
  expect_input_error(p, head41 + "$Nodes\n1 1 1 1\n3 1 0 1\n1\n0 0 0\n$EndNodes\n$Elements\n1 1 1 1\n3 1 4 1\n1 1 1 1 7\n$EndElements\n",
                     true, ":13: element 1 uses node tag 7, which no node has");
  expect_input_error(p, head41 + "$Nodes\n0 0 0 0\n$EndNodes\n$Elements\n1 1 1 1\n3 1 5 1\n", true,
                     "unsupported element type 5");
  expect_input_error(p, "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n2\n1 0 0 0\n1 1 1 1\n$EndNodes\n", true,
                     "node tag 1 is defined twice");
  const std::string m = scratch(".mesh");
  expect_input_error(m, "MeshVersionFormatted 2\nDimension 3\nVertices\n1\n0 0 0 0\nTetrahedra\n1\n1 1 1 2 1\n", false,
                     ":8: Tetrahedra element 1: vertex index 2 is outside 1..1");
  expect_input_error(m, "MeshVersionFormatted 2\nDimension 3\nVertices\n1\n0 0 0 0\nHexahedra\n", false,
                     "'Hexahedra' elements are not supported");
  expect_input_error(m, "MeshVersionFormatted 2\nDimension 2\n", false, ":2: Dimension 2");
  expect_input_error(m, "MeshVersionFormatted 2\nDimension 3\nVertices\n1\n0 0 0 0\nTetrahedra\n1\n1 1 1 1 0\n", false,
                     "ref 0");
}

/// Every prefix of a valid file (cut at many points) and many random byte changes either read
/// or fail with an InputError; nothing else may happen (run under ASan in CI).
TEST(FeReaders, TruncatedAndCorruptedFilesNeverCrash) {
  const FeMesh mesh = cube_mesh(2, 2);
  struct Variant {
    std::string ext;
    MshOptions msh;
    bool is_msh;
  };
  const Variant variants[] = {{".msh", {41, false}, true}, {".msh", {41, true}, true},
                              {".msh", {22, false}, true}, {".msh", {22, true}, true},
                              {".mesh", {}, false}};
  std::mt19937_64 rng(1234);
  int failures = 0, reads = 0;
  for (const Variant& v : variants) {
    const std::string path = scratch(v.ext);
    if (v.is_msh)
      write_msh(mesh, path, v.msh);
    else
      write_medit(mesh, path);
    const std::string good = slurp(path);
    const std::string bad = scratch(v.ext);
    auto attempt = [&](const std::string& bytes) {
      spit(bad, bytes);
      try {
        v.is_msh ? read_msh(bad) : read_medit(bad);
        ++reads;
      } catch (const InputError&) {
        ++failures;
      }
    };
    const std::size_t step = std::max<std::size_t>(1, good.size() / 53);
    for (std::size_t cut = 0; cut < good.size(); cut += step) attempt(good.substr(0, cut));
    for (int k = 0; k < 90; ++k) {
      std::string bytes = good;
      const int changes = 1 + int(rng() % 4);
      for (int c = 0; c < changes; ++c) {
        const std::size_t at = rng() % bytes.size();
        const char choices[] = {'0', '9', '-', ' ', '\n', '$', 'x', '\xff', '\0', '7'};
        bytes[at] = choices[rng() % sizeof choices];
      }
      attempt(bytes);
    }
  }
  EXPECT_GT(failures, 0);
  EXPECT_GT(reads, 0);
}

// =============================================================================================
// Real clients: gmsh, meshio (Debian python3-meshio, through /usr/bin/python3), ccx
// =============================================================================================

/// The "Info : minJ/maxJ = worst, avg, best" and "minJ = min, avg, max" figures of Gmsh's
/// AnalyseMeshQuality plugin for the tets of `msh`.
struct GmshQuality {
  double min_j = NAN, worst_ratio = NAN;
};
GmshQuality gmsh_quality(const std::string& msh) {
  const std::string geo = msh + ".quality.geo";
  spit(geo, "Merge \"" + msh + "\";\n"
            "Plugin(AnalyseMeshQuality).JacobianDeterminant = 1;\n"
            "Plugin(AnalyseMeshQuality).DimensionOfElements = 3;\n"
            "Plugin(AnalyseMeshQuality).CreateView = 0;\n"
            "Plugin(AnalyseMeshQuality).Run;\n");
  const ToolRun r = run("gmsh " + geo + " -parse_and_exit", geo);
  EXPECT_EQ(r.code, 0) << r.out;
  GmshQuality q;
  for (const std::string& line : lines_of(r.out)) {
    const auto eq = line.find('=');
    if (eq == std::string::npos) continue;
    if (line.find("minJ/maxJ") != std::string::npos)
      q.worst_ratio = std::stod(line.substr(eq + 1));
    else if (line.find("minJ ") != std::string::npos)
      q.min_j = std::stod(line.substr(eq + 1));
  }
  return q;
}

/// How many times an element of entity `e` (dimension d) appears in MSH 2.2: once per group
/// listing its entity, at least once (write_msh does what Gmsh does).
std::size_t copies_in_msh22(const FeMesh& m, int d, std::uint32_t e) {
  std::size_t n = 0;
  for (const FeGroup& g : m.groups)
    if (g.dim == d) n += std::size_t(std::count(g.entities.begin(), g.entities.end(), e));
  return std::max<std::size_t>(n, 1);
}

/// gmsh reads the file and saves it again as MSH 4.1; that file must hold the same mesh up to
/// renumbering (compared by coordinates), and Gmsh's own Jacobians must be positive (and
/// constant per element: straight-sided tet10 with correctly placed mid-edge nodes).
/// `repeats`: the file is MSH 2.2, whose per-group element copies Gmsh reads as distinct
/// elements (checked with a Gmsh-written 2.2 file: Gmsh does the same with its own), so every
/// element is expected copies_in_msh22 times.
void check_with_gmsh(const FeMesh& mesh, const std::string& file, bool repeats) {
  const std::string out = file + ".gmsh.msh";
  const ToolRun r = run("gmsh " + file + " -save -format msh41 -o " + out, out);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.find("Error"), std::string::npos) << r.out;
  const FeMesh back = read_msh(out);
  EXPECT_EQ(back.order, mesh.order);
  EXPECT_EQ(back.points.size(), mesh.points.size());
  EXPECT_EQ(misplaced_midnodes(back), 0);
  // Same elements with the same entities and node order, matched through the coordinates.
  using Element = std::pair<std::uint32_t, std::vector<std::array<double, 3>>>;
  auto elements = [](const FeMesh& m, int d, bool with_copies) {
    const auto& conn = d == 3 ? m.tets : d == 2 ? m.faces : m.edges;
    const auto& ent = d == 3 ? m.tet_entity : d == 2 ? m.face_entity : m.edge_entity;
    std::multiset<Element> s;
    const std::size_t nn = std::size_t(d == 3 ? m.tet_nodes() : d == 2 ? m.face_nodes() : m.edge_nodes());
    for (std::size_t e = 0; e < ent.size(); ++e) {
      Element el{ent[e], {}};
      for (std::size_t i = 0; i < nn; ++i) {
        const double* p = m.points.p(conn[e * nn + i]);
        el.second.push_back({p[0], p[1], p[2]});
      }
      const std::size_t n = with_copies ? copies_in_msh22(m, d, ent[e]) : 1;
      for (std::size_t c = 0; c < n; ++c) s.insert(el);
    }
    return s;
  };
  for (int d = 1; d <= 3; ++d) {
    const auto want = elements(mesh, d, repeats);
    const auto got = elements(back, d, false);
    EXPECT_EQ(got.size(), want.size()) << "dim " << d;
    EXPECT_TRUE(got == want) << "dim " << d;
  }
  std::set<std::pair<std::string, int>> want, got;
  for (const FeGroup& g : mesh.groups) want.emplace(g.name, g.dim);
  for (const FeGroup& g : back.groups) got.emplace(g.name, g.dim);
  if (file.size() < 5 || file.substr(file.size() - 5) != ".mesh") {
    EXPECT_EQ(got, want);  // MEDIT files carry no names Gmsh reads
  }
  double volume = 0, expected = 0;
  for (std::size_t t = 0; t < back.num_tets(); ++t) {
    EXPECT_GT(tet_volume(back, t), 0);
    volume += tet_volume(back, t);
  }
  for (std::size_t t = 0; t < mesh.num_tets(); ++t)
    expected += tet_volume(mesh, t) * double(repeats ? copies_in_msh22(mesh, 3, mesh.tet_entity[t]) : 1);
  EXPECT_NEAR(volume, expected, 1e-12);

  const GmshQuality q = gmsh_quality(file);
  EXPECT_GT(q.min_j, 0) << file;
  EXPECT_EQ(q.worst_ratio, 1.0) << file;
}

TEST(RealClients, GmshReadsMshAndMedit) {
  KDMESH_NEED_CLIENT(have_command("gmsh"), "gmsh");
  for (const int order : {1, 2}) {
    const FeMesh mesh = cube_mesh(2, order);
    for (const MshOptions o : {MshOptions{41, false}, MshOptions{41, true}, MshOptions{22, false},
                               MshOptions{22, true}}) {
      SCOPED_TRACE("order " + std::to_string(order) + ", MSH " + std::to_string(o.version) +
                   (o.binary ? " binary" : " ascii"));
      const std::string path = scratch(".msh");
      write_msh(mesh, path, o);
      check_with_gmsh(mesh, path, o.version == 22);
    }
    SCOPED_TRACE("order " + std::to_string(order) + ", MEDIT");
    const std::string path = scratch(".mesh");
    write_medit(mesh, path);
    check_with_gmsh(mesh, path, false);
  }
}

TEST(RealClients, GmshGeneratedTet10ReadsWithMidnodesInPlace) {
  KDMESH_NEED_CLIENT(have_command("gmsh"), "gmsh");
  const std::string geo = scratch(".geo");
  spit(geo, "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 2, 3};\n"
            "Physical Volume(\"body\") = {1};\nPhysical Surface(\"skin\") = {1, 2, 3, 4, 5, 6};\n"
            "Mesh.CharacteristicLengthMax = 0.7;\n");
  for (const std::string format : {"msh41", "msh22"}) {
    for (const bool binary : {false, true}) {
      const std::string msh = scratch(".msh");
      const ToolRun r = run("gmsh " + geo + " -3 -order 2 -format " + format + (binary ? " -bin" : "") +
                            " -o " + msh,
                        msh);
      ASSERT_EQ(r.code, 0) << r.out;
      const FeMesh m = read_msh(msh);
      EXPECT_EQ(m.order, 2);
      EXPECT_GT(m.num_tets(), 20u);
      EXPECT_GT(m.num_faces(), 20u);
      EXPECT_EQ(misplaced_midnodes(m, 1e-12), 0) << format;
      double volume = 0;
      for (std::size_t t = 0; t < m.num_tets(); ++t) volume += tet_volume(m, t);
      EXPECT_NEAR(volume, 6.0, 1e-9);
      ASSERT_EQ(m.groups.size(), 2u);
      EXPECT_EQ(m.groups[0].name, "body");
      EXPECT_EQ(m.groups[1].name, "skin");
      EXPECT_EQ(m.groups[1].entities.size(), 6u);
    }
  }
}

/// meshio's view of a file: "key values..." lines printed by the script below.
std::map<std::string, std::vector<std::string>> meshio_view(const std::string& file,
                                                            const std::string& format) {
  const std::string script = file + ".meshio.py";
  spit(script, R"PY(import sys
import numpy as np
import meshio
m = meshio.read(sys.argv[1], file_format=sys.argv[2])
print("points", len(m.points))
counts = {}
for c in m.cells:
    counts[c.type] = counts.get(c.type, 0) + len(c.data)
for t in sorted(counts):
    print("cells_" + t, counts[t])
vols, midbad = [], 0
for c in m.cells:
    if c.type not in ("tetra", "tetra10"):
        continue
    P = m.points[c.data[:, :4]]
    vols.extend(np.einsum("ij,ij->i", P[:, 1] - P[:, 0], np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 0])) / 6)
    if c.type == "tetra10":
        for k, (a, b) in enumerate([(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]):
            d = m.points[c.data[:, 4 + k]] - 0.5 * (m.points[c.data[:, a]] + m.points[c.data[:, b]])
            midbad += int((np.abs(d).max(axis=1) > 1e-12).sum())
vols = np.array(vols)
print("tets", len(vols))
print("nonpositive", int((vols <= 0).sum()))
print("volume", repr(float(vols.sum())))
print("midbad", midbad)
for name in sorted(m.field_data):
    print("field_" + name, *[int(x) for x in np.ravel(m.field_data[name])])
for name in sorted(m.cell_sets):
    print("cellset_" + name.lower(), sum(len(x) for x in m.cell_sets[name]))
for name in sorted(m.point_sets):
    print("pointset_" + name.lower(), len(m.point_sets[name]))
)PY");
  const ToolRun r = run("/usr/bin/python3 " + script + " " + file + " " + format, script);
  EXPECT_EQ(r.code, 0) << r.out;
  std::map<std::string, std::vector<std::string>> view;
  for (const std::string& line : lines_of(r.out)) {
    std::istringstream in(line);
    std::string key, v;
    in >> key;
    while (in >> v) view[key].push_back(v);
  }
  return view;
}

long num(const std::map<std::string, std::vector<std::string>>& view, const std::string& key) {
  const auto it = view.find(key);
  return it == view.end() || it->second.empty() ? -1 : std::stol(it->second[0]);
}

TEST(RealClients, MeshioReadsMshInpAndMedit) {
  KDMESH_NEED_CLIENT(have_meshio(), "meshio (python3-meshio)");
  for (const int order : {1, 2}) {
    const FeMesh mesh = cube_mesh(2, order);
    const std::string tet = order == 2 ? "cells_tetra10" : "cells_tetra";
    const std::string tri = order == 2 ? "cells_triangle6" : "cells_triangle";
    const std::string line = order == 2 ? "cells_line3" : "cells_line";
    // `copies`: meshio, like Gmsh, reads the per-group copies of MSH 2.2 as distinct elements
    // (24 right-half tets are in two volume groups; 48 side faces in two face groups).
    auto common = [&](const std::map<std::string, std::vector<std::string>>& v, bool copies) {
      EXPECT_EQ(num(v, "points"), long(mesh.points.size()));
      EXPECT_EQ(num(v, "tets"), long(mesh.num_tets()) + (copies ? 24 : 0));
      EXPECT_EQ(num(v, "nonpositive"), 0);
      ASSERT_TRUE(v.count("volume"));
      EXPECT_NEAR(std::stod(v.at("volume")[0]), copies ? 1.5 : 1.0, 1e-12);
      EXPECT_EQ(num(v, "midbad"), 0);
    };
    for (const MshOptions o : {MshOptions{41, false}, MshOptions{22, false}, MshOptions{41, true},
                               MshOptions{22, true}}) {
      SCOPED_TRACE("order " + std::to_string(order) + ", MSH " + std::to_string(o.version) +
                   (o.binary ? " binary" : " ascii"));
      const std::string path = scratch(".msh");
      write_msh(mesh, path, o);
      const auto v = meshio_view(path, "gmsh");
      common(v, o.version == 22);
      EXPECT_EQ(num(v, tet), long(mesh.num_tets()) + (o.version == 22 ? 24 : 0));
      EXPECT_EQ(num(v, tri), long(mesh.num_faces()) + (o.version == 22 ? 48 : 0));
      EXPECT_EQ(num(v, line), long(mesh.num_edges()));
      for (std::size_t g = 0; g < mesh.groups.size(); ++g) {
        const FeGroup& grp = mesh.groups[g];
        const auto it = v.find("field_" + grp.name);
        ASSERT_NE(it, v.end()) << grp.name;
        EXPECT_EQ(it->second, (std::vector<std::string>{std::to_string(g + 1), std::to_string(grp.dim)}));
        if (o.version == 41) {  // meshio turns MSH 4.1 physical groups into cell sets
          const auto& ent = grp.dim == 3 ? mesh.tet_entity : grp.dim == 2 ? mesh.face_entity : mesh.edge_entity;
          long members = 0;
          for (const std::uint32_t e : ent) members += std::count(grp.entities.begin(), grp.entities.end(), e);
          EXPECT_EQ(num(v, "cellset_" + grp.name), members) << grp.name;
        }
      }
    }
    {  // an entity in no group: not saved (Gmsh's default), which meshio 5 needs for 4.1
      SCOPED_TRACE("order " + std::to_string(order) + ", MSH 4.1 with an entity in no group");
      const FeMesh partial = cube_without_xmin_group(order);
      const std::string path = scratch(".msh");
      write_msh(partial, path);
      const auto v = meshio_view(path, "gmsh");
      const long xmin = long(std::count(partial.face_entity.begin(), partial.face_entity.end(), kSide0));
      EXPECT_EQ(num(v, tet), long(partial.num_tets()));
      EXPECT_EQ(num(v, tri), long(partial.num_faces()) - xmin);
    }
    {
      SCOPED_TRACE("order " + std::to_string(order) + ", INP");
      const std::string path = scratch(".inp");
      write_inp(mesh, path);
      const auto v = meshio_view(path, "abaqus");
      common(v, false);
      EXPECT_EQ(num(v, tet), long(mesh.num_tets()));
      EXPECT_EQ(num(v, "cellset_solid"), long(mesh.num_tets()));
      EXPECT_EQ(num(v, "cellset_right_half"), long(mesh.num_tets()) / 2);
      EXPECT_EQ(num(v, "pointset_solid"), long(mesh.points.size()));
      EXPECT_EQ(num(v, "pointset_xmin"), order == 2 ? 25 : 9);
    }
    if (order == 1) {  // meshio 5's MEDIT reader knows no P2 keywords
      SCOPED_TRACE("MEDIT");
      const std::string path = scratch(".mesh");
      write_medit(mesh, path);
      const auto v = meshio_view(path, "medit");
      common(v, false);
      EXPECT_EQ(num(v, tet), long(mesh.num_tets()));
      EXPECT_EQ(num(v, tri), long(mesh.num_faces()));
      EXPECT_EQ(num(v, line), long(mesh.num_edges()));
    }
  }
}

/// A linear-elastic bar (the unit cube, E, nu) under pressure p on its x = 1 face, with the
/// symmetry conditions u_x = 0 on x = 0, u_y = 0 on y = 0, u_z = 0 on z = 0 and no other
/// support. The exact solution is the uniform uniaxial stress sigma_xx = -p:
///   u_x = -p x / E,  u_y = nu p y / E,  u_z = nu p z / E,
/// which satisfies the symmetry conditions, leaves the lateral faces traction-free, and is
/// linear, so both C3D4 and C3D10 represent it exactly: every node must match it to the
/// printed precision of the .dat file (7 significant digits). The tip (x = 1) moves by p L / E.
/// The pressure goes through *DSLOAD on the *SURFACE "xmax", so a wrong face label would load
/// the wrong faces and show here.
void run_uniaxial_bar(int order) {
  const FeMesh mesh = cube_mesh(2, order);
  const std::string dir = scratch("-ccx-order" + std::to_string(order));
  fs::create_directories(dir);
  write_inp(mesh, dir + "/mesh.inp");
  const double E = 210000, nu = 0.3, p = 100;
  spit(dir + "/bar.inp",
       "*INCLUDE, INPUT=mesh.inp\n"
       "*MATERIAL, NAME=STEEL\n*ELASTIC\n210000., 0.3\n"
       "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n"
       "*STEP\n*STATIC\n"
       "*BOUNDARY\nxmin, 1, 1\nymin, 2, 2\nzmin, 3, 3\n"
       "*DSLOAD\nxmax, P, 100.\n"
       "*NODE FILE\nU\n"
       "*NODE PRINT, NSET=solid\nU\n"
       "*END STEP\n");
  const ToolRun r = run("cd " + dir + " && ccx -i bar", dir + "/ccx");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.find("*ERROR"), std::string::npos) << r.out;
  EXPECT_TRUE(fs::exists(dir + "/bar.frd"));

  // .dat: "displacements (vx,vy,vz) for set SOLID and time ..." then "node ux uy uz" lines.
  std::map<long, std::array<double, 3>> u;
  bool in_block = false;
  for (const std::string& line : lines_of(slurp(dir + "/bar.dat"))) {
    if (line.find("displacements") != std::string::npos) {
      in_block = true;
      continue;
    }
    if (!in_block) continue;
    std::istringstream in(line);
    long node;
    std::array<double, 3> d;
    if (in >> node >> d[0] >> d[1] >> d[2]) u[node] = d;
  }
  ASSERT_EQ(u.size(), mesh.points.size());
  const double scale = p / E;
  double tip = 0;
  for (std::size_t n = 0; n < mesh.points.size(); ++n) {
    const double* x = mesh.points.p(std::uint32_t(n));
    const auto& d = u.at(long(n) + 1);
    for (int c = 0; c < 3; ++c) ASSERT_TRUE(std::isfinite(d[c]));
    EXPECT_NEAR(d[0], -p * x[0] / E, 1e-5 * scale) << "node " << n + 1;
    EXPECT_NEAR(d[1], nu * p * x[1] / E, 1e-5 * scale) << "node " << n + 1;
    EXPECT_NEAR(d[2], nu * p * x[2] / E, 1e-5 * scale) << "node " << n + 1;
    if (x[0] == 1) tip = d[0];
  }
  EXPECT_NEAR(tip, -p * 1.0 / E, 1e-5 * scale);
}

TEST(RealClients, CalculixUniaxialBarC3D4) {
  KDMESH_NEED_CLIENT(have_command("ccx"), "ccx");
  run_uniaxial_bar(1);
}

TEST(RealClients, CalculixUniaxialBarC3D10) {
  KDMESH_NEED_CLIENT(have_command("ccx"), "ccx");
  run_uniaxial_bar(2);
}

}  // namespace
}  // namespace kdmesh
