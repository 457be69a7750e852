// kdmesh — Abaqus / CalculiX .inp writer for FeMesh (mesh part of an input deck).
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// References: Abaqus Analysis User's Guide, "*ELEMENT", "*SURFACE" and the C3D4 / C3D10 face
// numbering of "Three-dimensional solid element library"; CalculiX CrunchiX User's Manual
// (v2.20) section 6.2 (element types C3D4 / C3D10, same node and face numbering) and the input
// deck format (set names up to 80 characters; *NODE reads the first 20 characters of each
// coordinate field, ccx source nodes.f).
#include "io/inp_writer.h"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "io/fe_mesh_index.h"
#include "io/file_io.h"
#include "io/text_sink.h"

namespace kdmesh {

namespace {

/// Corner positions (0-based) of the Abaqus faces S1..S4 of a C3D4 / C3D10 element, as the
/// manuals list them. For a positively oriented tet (FeMesh / VTK convention) each listing
/// turns so that its right-hand normal points INTO the tet.
constexpr int kAbaqusFace[4][3] = {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {2, 3, 0}};

constexpr std::size_t kMaxLine = 80;
constexpr int kMaxEntries = 16;
/// CalculiX reads the first 20 characters of each *NODE coordinate field (nodes.f), after
/// removing blanks (checked with ccx 2.20: a 20-character value after ", " reads back exactly).
constexpr int kCoordinateWidth = 20;

std::string upper(std::string s) {
  for (char& c : s) c = char(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

std::size_t digits(std::uint64_t v) {
  std::size_t n = 1;
  while (v >= 10) {
    v /= 10;
    ++n;
  }
  return n;
}

/// Writes a list of ids, breaking lines at 16 entries or before 80 characters.
void write_id_list(TextSink& s, const std::vector<std::uint32_t>& ids_0based) {
  std::size_t line_len = 0;
  int entries = 0;
  for (const std::uint32_t id0 : ids_0based) {
    const std::uint64_t id = std::uint64_t(id0) + 1;
    const std::size_t len = digits(id);
    if (entries > 0 && (entries == kMaxEntries || line_len + 2 + len > kMaxLine)) {
      s.put(",\n");
      line_len = 0;
      entries = 0;
    }
    if (entries > 0) {
      s.put(", ");
      line_len += 2;
    }
    s.put_uint(id);
    line_len += len;
    ++entries;
  }
  if (entries > 0) s.put('\n');
}

/// Checks set names for Abaqus / CalculiX (see the header).
void check_names(const FeMesh& mesh, const InpOptions& options) {
  auto check_one = [](const std::string& name, const std::string& what) {
    if (name.empty()) throw UsageError("write_inp: " + what + " is empty");
    if (name.size() > 80)
      throw UsageError("write_inp: " + what + " '" + name + "' is longer than 80 characters");
    if (!std::isalpha(static_cast<unsigned char>(name[0])))
      throw UsageError("write_inp: " + what + " '" + name + "' does not start with a letter");
    for (const char c : name)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-')
        throw UsageError("write_inp: " + what + " '" + name +
                         "' has a character outside [A-Za-z0-9_-]");
  };
  check_one(options.all_elset, "the all-tets ELSET name");
  check_one(options.all_nset, "the all-nodes NSET name");
  if (options.heading.find_first_of("\r\n") != std::string::npos)
    throw UsageError("write_inp: the heading has a line break");
  std::vector<std::pair<std::string, std::size_t>> seen;
  for (std::size_t g = 0; g < mesh.groups.size(); ++g) {
    check_one(mesh.groups[g].name, "group " + std::to_string(g) + " name");
    seen.emplace_back(upper(mesh.groups[g].name), g);
  }
  std::sort(seen.begin(), seen.end());
  for (std::size_t i = 1; i < seen.size(); ++i)
    if (seen[i].first == seen[i - 1].first)
      throw UsageError("write_inp: groups '" + mesh.groups[seen[i - 1].second].name + "' and '" +
                       mesh.groups[seen[i].second].name +
                       "' have the same Abaqus set name (names are case-insensitive and every "
                       "group gets an NSET)");
  const std::string all_tets = upper(options.all_elset), all_nodes = upper(options.all_nset);
  for (const auto& [name, g] : seen) {
    if (name == all_tets)
      throw UsageError("write_inp: group '" + mesh.groups[g].name +
                       "' has the name of the all-tets ELSET '" + options.all_elset + "'");
    if (name == all_nodes)
      throw UsageError("write_inp: group '" + mesh.groups[g].name +
                       "' has the name of the all-nodes NSET '" + options.all_nset + "'");
  }
}

}  // namespace

int abaqus_face_label(const std::uint32_t* tet, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  return local_face_of(tet, kAbaqusFace, a, b, c) + 1;
}

void write_inp(const FeMesh& mesh, const std::string& path, const InpOptions& options) {
  const FeIndex index = index_fe_mesh(mesh, "write_inp");
  check_names(mesh, options);

  // Match every group face to its tet first: a failure must not leave a file behind.
  const GroupFaceOwners owners = match_group_faces(mesh, index, kAbaqusFace, "write_inp", "a *SURFACE");
  AtomicFile file(path);
  FileWriter writer(file.temp_path(), path);
  TextSink s(writer);
  const std::size_t np = mesh.points.size();
  const std::size_t nt = mesh.num_tets();
  const char* type = mesh.order == 2 ? "C3D10" : "C3D4";

  s.put("** kdmesh: ").put_uint(np).put(" nodes, ").put_uint(nt).put(' ').put(type)
      .put(" elements, ").put_uint(mesh.groups.size()).put(" groups\n");
  s.put("*HEADING\n").put(options.heading).put('\n');

  s.put("*NODE, NSET=").put(options.all_nset).put('\n');
  for (std::size_t n = 0; n < np; ++n) {
    const double* p = mesh.points.p(std::uint32_t(n));
    s.put_uint(n + 1);
    for (int c = 0; c < 3; ++c) s.put(", ").put_real_width(p[c], kCoordinateWidth);
    s.put('\n');
  }

  s.put("*ELEMENT, TYPE=").put(type).put(", ELSET=").put(options.all_elset).put('\n');
  const std::size_t tn = std::size_t(mesh.tet_nodes());
  for (std::size_t t = 0; t < nt; ++t) {
    const std::uint32_t* el = mesh.tets.data() + t * tn;
    s.put_uint(t + 1);
    for (std::size_t i = 0; i < tn; ++i) {
      // C3D10: 5 nodes per line, so that 10-digit ids stay within 80 characters.
      s.put(i == 5 ? ",\n" : ", ");
      s.put_uint(std::uint64_t(el[i]) + 1);
    }
    s.put('\n');
  }

  for (std::size_t g = 0; g < mesh.groups.size(); ++g) {
    const FeGroup& grp = mesh.groups[g];
    const EntityTable& t = index.dim[grp.dim];
    if (grp.dim == 3) {
      std::vector<std::uint32_t> tets;
      for (const std::uint32_t e : grp.entities) {
        const std::size_t k = t.find(e);
        tets.insert(tets.end(), t.element_of.begin() + std::ptrdiff_t(t.start[k]),
                    t.element_of.begin() + std::ptrdiff_t(t.start[k + 1]));
      }
      std::sort(tets.begin(), tets.end());
      tets.erase(std::unique(tets.begin(), tets.end()), tets.end());
      s.put("*ELSET, ELSET=").put(grp.name).put('\n');
      write_id_list(s, tets);
    }
    s.put("*NSET, NSET=").put(grp.name).put('\n');
    write_id_list(s, group_nodes(mesh, index, g));
    if (grp.dim == 2) {
      s.put("*SURFACE, NAME=").put(grp.name).put(", TYPE=ELEMENT\n");
      std::vector<std::uint32_t> entities = grp.entities;
      std::sort(entities.begin(), entities.end());
      entities.erase(std::unique(entities.begin(), entities.end()), entities.end());
      for (const std::uint32_t e : entities) {
        const std::size_t k = t.find(e);
        for (std::size_t j = t.start[k]; j < t.start[k + 1]; ++j) {
          const std::uint32_t slot = owners.slot_of_face[t.element_of[j]];
          s.put_uint(std::uint64_t(owners.tet[slot]) + 1).put(", S").put_uint(owners.face[slot] + 1u)
              .put('\n');
        }
      }
    }
  }
  s.flush();
  writer.close();
  file.commit();
}

}  // namespace kdmesh
