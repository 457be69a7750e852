// kdmesh — MEDIT / Gamma Mesh Format (.mesh, ASCII) writer for FeMesh.
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Reference: libMeshb 7 documentation (Documentation/libMeshb7.pdf in LoicMarechal/libMeshb):
// keyword list, "MeshVersionFormatted 2" = double precision reals, P2 element keywords.
#include "io/medit_writer.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "io/fe_mesh_index.h"
#include "io/file_io.h"
#include "io/text_sink.h"

namespace kdmesh {

namespace {

/// The group comment lines: "# kdmesh-group <dim> <name>" followed by refs, wrapped so that no
/// line exceeds 80 characters (after the first ref).
void write_group_comments(TextSink& s, const FeMesh& mesh) {
  for (const FeGroup& g : mesh.groups) {
    std::vector<std::uint32_t> entities = g.entities;
    std::sort(entities.begin(), entities.end());
    entities.erase(std::unique(entities.begin(), entities.end()), entities.end());
    const std::string head = "# kdmesh-group " + std::to_string(g.dim) + " " + g.name;
    std::size_t len = 0;
    for (std::size_t i = 0; i < entities.size(); ++i) {
      const std::string ref = std::to_string(std::uint64_t(entities[i]) + 1);
      if (i == 0 || len + 1 + ref.size() > 80) {
        if (i > 0) s.put('\n');
        s.put(head);
        len = head.size();
      }
      s.put(' ').put(ref);
      len += 1 + ref.size();
    }
    s.put('\n');
  }
}

void write_elements(TextSink& s, const FeMesh& mesh, int d) {
  const auto& conn = connectivity(mesh, d);
  const auto& ent = entity_array(mesh, d);
  if (ent.empty()) return;
  static const char* const kP1[4] = {"", "Edges", "Triangles", "Tetrahedra"};
  static const char* const kP2[4] = {"", "EdgesP2", "TrianglesP2", "TetrahedraP2"};
  s.put('\n').put(mesh.order == 2 ? kP2[d] : kP1[d]).put('\n').put_uint(ent.size()).put('\n');
  const std::size_t nn = std::size_t(nodes_per_element(mesh, d));
  for (std::size_t e = 0; e < ent.size(); ++e) {
    const std::uint32_t* el = conn.data() + e * nn;
    for (std::size_t i = 0; i < nn; ++i) s.put_uint(std::uint64_t(el[i]) + 1).put(' ');
    s.put_uint(std::uint64_t(ent[e]) + 1).put('\n');
  }
}

}  // namespace

void write_medit(const FeMesh& mesh, const std::string& path) {
  const FeIndex index = index_fe_mesh(mesh, "write_medit");
  constexpr std::uint32_t kMaxEntity = std::uint32_t(std::numeric_limits<std::int32_t>::max()) - 1;
  for (int d = 1; d <= 3; ++d)
    if (!index.dim[d].ids.empty() && index.dim[d].ids.back() > kMaxEntity)
      throw UsageError("write_medit: entity id " + std::to_string(index.dim[d].ids.back()) +
                       " (dim " + std::to_string(d) + ") exceeds 2^31 - 2: MEDIT refs are ints");

  AtomicFile file(path);
  FileWriter writer(file.temp_path(), path);
  TextSink s(writer);
  s.put("MeshVersionFormatted 2\n\nDimension 3\n\n");
  write_group_comments(s, mesh);
  const std::size_t np = mesh.points.size();
  s.put("\nVertices\n").put_uint(np).put('\n');
  for (std::size_t n = 0; n < np; ++n) {
    const double* p = mesh.points.p(std::uint32_t(n));
    s.put_real(p[0]).put(' ').put_real(p[1]).put(' ').put_real(p[2]).put(" 0\n");
  }
  write_elements(s, mesh, 3);
  write_elements(s, mesh, 2);
  write_elements(s, mesh, 1);
  s.put("\nEnd\n");
  s.flush();
  writer.close();
  file.commit();
}

}  // namespace kdmesh
