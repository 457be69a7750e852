// kdmesh — Gmsh MSH writer (format 4.1 or 2.2, ASCII or binary) for FeMesh.
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Reference: the Gmsh reference manual, section "MSH file format" (4.1 and the legacy 2.2),
// and its node-ordering figures. Everything is streamed through one TextSink buffer; the only
// per-node / per-element arrays are the entity buckets of index_fe_mesh and, for 4.1, the
// entity block of each node.
#include "io/msh_writer.h"

#include <algorithm>
#include <array>
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

/// Gmsh's tet10 node i is FeMesh's (VTK's) node kGmshTet10[i]: the last two mid-edge nodes
/// are swapped (Gmsh: (2,3) then (1,3); VTK: (1,3) then (2,3)). Other types need no change.
constexpr int kGmshTet10[10] = {0, 1, 2, 3, 4, 5, 6, 7, 9, 8};

int gmsh_type(int dim, int order) {
  if (dim == 3) return order == 2 ? 11 : 4;
  if (dim == 2) return order == 2 ? 9 : 2;
  return order == 2 ? 8 : 1;
}

/// One value sink for both encodings: ASCII writes the value then `sep`; binary writes the
/// value's bytes (size_t as uint64, int as int32, double as double) and no separator.
class MshOut {
 public:
  MshOut(TextSink& s, bool binary) : s_(s), bin_(binary) {}
  void size(std::uint64_t v, char sep) {
    if (bin_)
      s_.put_binary(v);
    else
      s_.put_uint(v).put(sep);
  }
  void integer(std::int64_t v, char sep) {
    if (bin_)
      s_.put_binary(std::int32_t(v));
    else
      s_.put_int(v).put(sep);
  }
  void real(double v, char sep) {
    if (bin_)
      s_.put_binary(v);
    else
      s_.put_real(v).put(sep);
  }
  /// Text that is the same in both encodings (section markers, ASCII counts of MSH 2.2).
  void text(std::string_view t) { s_.put(t); }
  /// After binary data, the section end marker starts on a new line (Gmsh writes it so).
  void end_section(std::string_view marker) {
    if (bin_) s_.put('\n');
    s_.put(marker).put('\n');
  }
  bool binary() const { return bin_; }
  TextSink& sink() { return s_; }

 private:
  TextSink& s_;
  bool bin_;
};

/// Element node `i` in Gmsh order.
inline std::uint32_t gmsh_node(const std::uint32_t* el, int dim, int order, int i) {
  return dim == 3 && order == 2 ? el[kGmshTet10[i]] : el[i];
}

void write_header(MshOut& out, const char* version) {
  out.text("$MeshFormat\n");
  out.text(version);
  out.text(out.binary() ? " 1 8\n" : " 0 8\n");
  if (out.binary()) {
    const std::int32_t one = 1;  // lets the reader detect the byte order
    out.sink().put_binary(one);
    out.text("\n");
  }
  out.text("$EndMeshFormat\n");
}

void write_physical_names(TextSink& s, const FeMesh& mesh) {
  if (mesh.groups.empty()) return;
  s.put("$PhysicalNames\n").put_uint(mesh.groups.size()).put('\n');
  for (std::size_t g = 0; g < mesh.groups.size(); ++g)
    s.put_int(mesh.groups[g].dim).put(' ').put_uint(g + 1).put(" \"").put(mesh.groups[g].name)
        .put("\"\n");
  s.put("$EndPhysicalNames\n");
}

/// The bounding box (min xyz, max xyz) of the nodes of entity k of dimension d.
std::array<double, 6> entity_box(const FeMesh& mesh, const EntityTable& t, int d, std::size_t k) {
  std::array<double, 6> b = {std::numeric_limits<double>::infinity(),
                             std::numeric_limits<double>::infinity(),
                             std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity()};
  const auto& conn = connectivity(mesh, d);
  const std::size_t nn = std::size_t(nodes_per_element(mesh, d));
  for (std::size_t j = t.start[k]; j < t.start[k + 1]; ++j) {
    const std::uint32_t* el = conn.data() + std::size_t(t.element_of[j]) * nn;
    for (std::size_t i = 0; i < nn; ++i) {
      const double* p = mesh.points.p(el[i]);
      for (int c = 0; c < 3; ++c) {
        b[c] = std::min(b[c], p[c]);
        b[3 + c] = std::max(b[3 + c], p[c]);
      }
    }
  }
  return b;
}

void write_entities(MshOut& out, const FeMesh& mesh, const FeIndex& index) {
  out.text("$Entities\n");
  out.size(0, ' ');  // no point entities
  out.size(index.dim[1].size(), ' ');
  out.size(index.dim[2].size(), ' ');
  out.size(index.dim[3].size(), '\n');
  for (int d = 1; d <= 3; ++d) {
    const EntityTable& t = index.dim[d];
    for (std::size_t k = 0; k < t.size(); ++k) {
      out.integer(std::int64_t(t.ids[k]) + 1, ' ');
      const auto box = entity_box(mesh, t, d, k);
      for (const double v : box) out.real(v, ' ');
      out.size(t.gstart[k + 1] - t.gstart[k], ' ');
      for (std::size_t j = t.gstart[k]; j < t.gstart[k + 1]; ++j)
        out.integer(std::int64_t(t.group_of[j]) + 1, ' ');
      out.size(0, '\n');  // no bounding entities
    }
  }
  out.end_section("$EndEntities");
}

/// MSH 4.1 $Nodes: one block per entity holding the nodes classified on it (see the header).
void write_nodes_41(MshOut& out, const FeMesh& mesh, const FeIndex& index) {
  const std::size_t np = mesh.points.size();
  // Blocks: the entities of dimension 1, then 2, then 3, in table order.
  std::array<std::size_t, 4> first_block = {0, 0, 0, 0};
  std::size_t nblocks_all = 0;
  for (int d = 1; d <= 3; ++d) {
    first_block[d] = nblocks_all;
    nblocks_all += index.dim[d].size();
  }
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> block(np, kNone);
  for (int d = 1; d <= 3; ++d) {
    const EntityTable& t = index.dim[d];
    const auto& conn = connectivity(mesh, d);
    const std::size_t nn = std::size_t(nodes_per_element(mesh, d));
    for (std::size_t k = 0; k < t.size(); ++k)
      for (std::size_t j = t.start[k]; j < t.start[k + 1]; ++j) {
        const std::uint32_t* el = conn.data() + std::size_t(t.element_of[j]) * nn;
        for (std::size_t i = 0; i < nn; ++i)
          if (block[el[i]] == kNone) block[el[i]] = std::uint32_t(first_block[d] + k);
      }
  }
  // Points used by no element: on the first volume, else surface, else curve.
  std::uint32_t spare = kNone;
  for (int d = 3; d >= 1 && spare == kNone; --d)
    if (index.dim[d].size() > 0) spare = std::uint32_t(first_block[d]);
  for (std::size_t n = 0; n < np; ++n)
    if (block[n] == kNone) {
      if (spare == kNone)
        throw UsageError("write_msh: the mesh has " + std::to_string(np) +
                         " points but no elements: MSH 4.1 needs an entity to hold them");
      block[n] = spare;
    }

  // Counting sort of the nodes by block (ascending node id within a block).
  std::vector<std::size_t> start(nblocks_all + 1, 0);
  for (const std::uint32_t b : block) ++start[b + 1];
  for (std::size_t b = 0; b < nblocks_all; ++b) start[b + 1] += start[b];
  std::vector<std::uint32_t> order(np);
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t n = 0; n < np; ++n) order[fill[block[n]]++] = std::uint32_t(n);
  }
  std::vector<std::uint32_t>().swap(block);

  std::size_t nonempty = 0;
  for (std::size_t b = 0; b < nblocks_all; ++b) nonempty += start[b + 1] > start[b];
  out.text("$Nodes\n");
  out.size(nonempty, ' ');
  out.size(np, ' ');
  out.size(np ? 1 : 0, ' ');
  out.size(np, '\n');
  for (int d = 1; d <= 3; ++d) {
    const EntityTable& t = index.dim[d];
    for (std::size_t k = 0; k < t.size(); ++k) {
      const std::size_t b = first_block[d] + k;
      if (start[b + 1] == start[b]) continue;
      out.integer(d, ' ');
      out.integer(std::int64_t(t.ids[k]) + 1, ' ');
      out.integer(0, ' ');  // not parametric
      out.size(start[b + 1] - start[b], '\n');
      for (std::size_t j = start[b]; j < start[b + 1]; ++j) out.size(std::uint64_t(order[j]) + 1, '\n');
      for (std::size_t j = start[b]; j < start[b + 1]; ++j) {
        const double* p = mesh.points.p(order[j]);
        out.real(p[0], ' ');
        out.real(p[1], ' ');
        out.real(p[2], '\n');
      }
    }
  }
  out.end_section("$EndNodes");
}

/// Element tag offsets: tets start at 1, faces after the tets, edges after the faces.
std::array<std::uint64_t, 4> element_tag_base(const FeMesh& mesh) {
  return {0, mesh.num_tets() + mesh.num_faces(), mesh.num_tets(), 0};
}

void write_elements_41(MshOut& out, const FeMesh& mesh, const FeIndex& index, bool save_all) {
  const auto base = element_tag_base(mesh);
  // Gmsh's rule (its Mesh.SaveAll = 0): once the mesh has physical groups, only the elements of
  // entities in some group are saved. meshio 5 also needs it: it refuses a 4.1 file in which
  // some element blocks have physical tags and others have none.
  const bool grouped_only = !save_all && !mesh.groups.empty();
  auto written = [&](const EntityTable& t, std::size_t k) {
    return !grouped_only || t.gstart[k + 1] > t.gstart[k];
  };
  std::uint64_t blocks = 0, total = 0;
  std::uint64_t min_tag = std::numeric_limits<std::uint64_t>::max(), max_tag = 0;
  for (int d = 1; d <= 3; ++d) {
    const EntityTable& t = index.dim[d];
    for (std::size_t k = 0; k < t.size(); ++k) {
      if (!written(t, k)) continue;
      ++blocks;
      total += t.num_elements(k);
      for (std::size_t j = t.start[k]; j < t.start[k + 1]; ++j) {
        min_tag = std::min<std::uint64_t>(min_tag, base[d] + t.element_of[j] + 1);
        max_tag = std::max<std::uint64_t>(max_tag, base[d] + t.element_of[j] + 1);
      }
    }
  }
  out.text("$Elements\n");
  out.size(blocks, ' ');
  out.size(total, ' ');
  out.size(total ? min_tag : 0, ' ');
  out.size(total ? max_tag : 0, '\n');
  for (int d = 1; d <= 3; ++d) {
    const EntityTable& t = index.dim[d];
    const auto& conn = connectivity(mesh, d);
    const int nn = nodes_per_element(mesh, d);
    for (std::size_t k = 0; k < t.size(); ++k) {
      if (!written(t, k)) continue;
      out.integer(d, ' ');
      out.integer(std::int64_t(t.ids[k]) + 1, ' ');
      out.integer(gmsh_type(d, mesh.order), ' ');
      out.size(t.num_elements(k), '\n');
      for (std::size_t j = t.start[k]; j < t.start[k + 1]; ++j) {
        const std::uint32_t e = t.element_of[j];
        const std::uint32_t* el = conn.data() + std::size_t(e) * std::size_t(nn);
        out.size(base[d] + e + 1, ' ');
        for (int i = 0; i < nn; ++i)
          out.size(std::uint64_t(gmsh_node(el, d, mesh.order, i)) + 1, i + 1 < nn ? ' ' : '\n');
      }
    }
  }
  out.end_section("$EndElements");
}

void write_nodes_22(MshOut& out, const FeMesh& mesh) {
  const std::size_t np = mesh.points.size();
  out.text("$Nodes\n");
  out.sink().put_uint(np).put('\n');  // the count is ASCII in both encodings
  for (std::size_t n = 0; n < np; ++n) {
    const double* p = mesh.points.p(std::uint32_t(n));
    out.integer(std::int64_t(n) + 1, ' ');
    out.real(p[0], ' ');
    out.real(p[1], ' ');
    out.real(p[2], '\n');
  }
  out.end_section("$EndNodes");
}

void write_elements_22(MshOut& out, const FeMesh& mesh, const FeIndex& index) {
  // Copies: element e of dimension d is written once per group of its entity (physical tag =
  // group + 1), or once with physical 0. The first copy keeps the element's own tag; the others
  // are numbered after every element.
  std::uint64_t extra = 0;
  for (int d = 1; d <= 3; ++d) {
    const EntityTable& t = index.dim[d];
    for (std::size_t k = 0; k < t.size(); ++k) {
      const std::size_t ng = t.gstart[k + 1] - t.gstart[k];
      if (ng > 1) extra += (ng - 1) * t.num_elements(k);
    }
  }
  const auto base = element_tag_base(mesh);
  const std::uint64_t total = mesh.num_tets() + mesh.num_faces() + mesh.num_edges();
  if (out.binary() && total + extra > std::uint64_t(std::numeric_limits<std::int32_t>::max()))
    throw UsageError("write_msh: " + std::to_string(total + extra) +
                     " elements do not fit the int tags of binary MSH 2.2");
  out.text("$Elements\n");
  out.sink().put_uint(total + extra).put('\n');

  // One pass writes the first copies in tag order (tets, faces, edges), the next the copies.
  auto write_one = [&](int d, std::uint32_t e, std::uint64_t tag, std::int64_t physical) {
    const auto& conn = connectivity(mesh, d);
    const int nn = nodes_per_element(mesh, d);
    const std::uint32_t* el = conn.data() + std::size_t(e) * std::size_t(nn);
    const std::int64_t elementary = std::int64_t(entity_array(mesh, d)[e]) + 1;
    if (out.binary()) {
      out.integer(std::int64_t(tag), ' ');
      out.integer(physical, ' ');
      out.integer(elementary, ' ');
      for (int i = 0; i < nn; ++i) out.integer(std::int64_t(gmsh_node(el, d, mesh.order, i)) + 1, ' ');
      return;
    }
    TextSink& s = out.sink();
    s.put_uint(tag).put(' ').put_int(gmsh_type(d, mesh.order)).put(" 2 ").put_int(physical).put(' ')
        .put_int(elementary);
    for (int i = 0; i < nn; ++i) s.put(' ').put_uint(std::uint64_t(gmsh_node(el, d, mesh.order, i)) + 1);
    s.put('\n');
  };
  // Binary MSH 2.2 groups elements under headers (type, count, number of tags).
  auto binary_header = [&](int d, std::uint64_t count) {
    if (!out.binary() || count == 0) return;
    out.integer(gmsh_type(d, mesh.order), ' ');
    out.integer(std::int64_t(count), ' ');
    out.integer(2, ' ');
  };

  const int dims[3] = {3, 2, 1};  // tag order
  for (const int d : dims) {
    const EntityTable& t = index.dim[d];
    const auto& ent = entity_array(mesh, d);
    binary_header(d, ent.size());
    std::size_t k = 0;
    std::uint32_t last = 0;
    bool have_last = false;
    for (std::uint32_t e = 0; e < ent.size(); ++e) {
      if (!have_last || ent[e] != last) {
        k = t.find(ent[e]);
        last = ent[e];
        have_last = true;
      }
      const std::int64_t physical =
          t.gstart[k + 1] > t.gstart[k] ? std::int64_t(t.group_of[t.gstart[k]]) + 1 : 0;
      write_one(d, e, base[d] + e + 1, physical);
    }
  }
  std::uint64_t tag = total;
  for (const int d : dims) {
    const EntityTable& t = index.dim[d];
    std::uint64_t count = 0;
    for (std::size_t k = 0; k < t.size(); ++k) {
      const std::size_t ng = t.gstart[k + 1] - t.gstart[k];
      if (ng > 1) count += (ng - 1) * t.num_elements(k);
    }
    binary_header(d, count);
    for (std::size_t k = 0; k < t.size(); ++k)
      for (std::size_t gi = t.gstart[k] + 1; gi < t.gstart[k + 1]; ++gi)
        for (std::size_t j = t.start[k]; j < t.start[k + 1]; ++j)
          write_one(d, t.element_of[j], ++tag, std::int64_t(t.group_of[gi]) + 1);
  }
  out.end_section("$EndElements");
}

}  // namespace

void write_msh(const FeMesh& mesh, const std::string& path, MshOptions options) {
  if (options.version != 41 && options.version != 22)
    throw UsageError("write_msh: version " + std::to_string(options.version) +
                     " is not supported (41 or 22)");
  const FeIndex index = index_fe_mesh(mesh, "write_msh");
  constexpr std::uint32_t kMaxEntity = std::uint32_t(std::numeric_limits<std::int32_t>::max()) - 1;
  for (int d = 1; d <= 3; ++d)
    if (!index.dim[d].ids.empty() && index.dim[d].ids.back() > kMaxEntity)
      throw UsageError("write_msh: entity id " + std::to_string(index.dim[d].ids.back()) +
                       " (dim " + std::to_string(d) + ") exceeds 2^31 - 2: Gmsh tags are ints");
  if (options.version == 22 && options.binary &&
      mesh.points.size() > std::size_t(std::numeric_limits<std::int32_t>::max()))
    throw UsageError("write_msh: too many points for the int tags of binary MSH 2.2");

  AtomicFile file(path);
  FileWriter writer(file.temp_path(), path);
  TextSink sink(writer);
  MshOut out(sink, options.binary);
  if (options.version == 41) {
    write_header(out, "4.1");
    write_physical_names(sink, mesh);
    write_entities(out, mesh, index);
    write_nodes_41(out, mesh, index);
    write_elements_41(out, mesh, index, options.save_all);
  } else {
    write_header(out, "2.2");
    write_physical_names(sink, mesh);
    write_nodes_22(out, mesh);
    write_elements_22(out, mesh, index);
  }
  sink.flush();
  writer.close();
  file.commit();
}

}  // namespace kdmesh
