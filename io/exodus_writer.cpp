// kdmesh — Exodus II writer for FeMesh.
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// References: "EXODUS II: A Finite Element Data Model" (Sandia SAND92-2137, Schoof and Yarberry),
// the element types (TETRA4 / TETRA10 node order) and side set numbering of its section 3 and
// appendix; the Exodus C API (SEACAS exodus 8.11 as VTK 9.1 builds and ships it: the target
// VTK::exodusII, header vtk_exodusII.h, symbols prefixed vtkexodusII_).
#include "io/exodus_writer.h"

#include <vtk_exodusII.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "io/fe_mesh_index.h"

namespace kdmesh {

namespace {

/// Corner positions (0-based) of the Exodus tet sides 1..4, each listed so that its right-hand
/// normal points INTO a positively oriented tet (the manual's outward listings (1,2,4) (2,3,4)
/// (1,4,3) (1,3,2) reversed), as match_group_faces wants them.
constexpr int kExodusSideInward[4][3] = {{0, 3, 1}, {1, 3, 2}, {0, 2, 3}, {0, 1, 2}};

/// The Exodus library keeps process-wide state (its options, error value and per-file lists):
/// its calls are serialised, as two jobs of one batch may write at once.
std::mutex& exodus_mutex() {
  static std::mutex m;
  return m;
}

constexpr std::int64_t kMaxInt = std::numeric_limits<int>::max();

void check_fits(std::uint64_t v, const std::string& what) {
  if (v > std::uint64_t(kMaxInt))
    throw UsageError("write_exodus: " + what + " " + std::to_string(v) +
                     " exceeds 2^31 - 1: the file's integers are 32-bit");
}

/// An open Exodus file, closed at scope exit; every failed call becomes an OutputError.
class ExodusFile {
 public:
  ExodusFile(const std::string& file, const std::string& report_as) : report_as_(report_as) {
    int cpu_ws = sizeof(double), io_ws = sizeof(double);
    // the temporary exists (created exclusively by AtomicFile): EX_CLOBBER truncates it
    id_ = ex_create(file.c_str(), EX_CLOBBER | EX_LARGE_MODEL, &cpu_ws, &io_ws);
    if (id_ < 0) throw OutputError(report_as_, "Exodus: cannot create the file");
  }
  ~ExodusFile() {
    if (id_ >= 0) ex_close(id_);
  }
  ExodusFile(const ExodusFile&) = delete;
  ExodusFile& operator=(const ExodusFile&) = delete;
  int id() const { return id_; }
  /// Throws OutputError("Exodus: cannot <what>") if `status` is an error (< 0).
  void check(int status, const std::string& what) const {
    if (status < 0) throw OutputError(report_as_, "Exodus: cannot " + what);
  }
  void close() {
    const int id = id_;
    id_ = -1;
    check(ex_close(id), "close the file");
  }

 private:
  std::string report_as_;
  int id_ = -1;
};

/// Writes `names` (one per entity of `type`, in definition order) with ex_put_names.
void put_names(const ExodusFile& f, ex_entity_type type, const std::vector<std::string>& names,
               const char* what) {
  if (names.empty()) return;
  std::vector<char*> ptrs;
  for (const std::string& n : names) ptrs.push_back(const_cast<char*>(n.c_str()));
  f.check(ex_put_names(f.id(), type, ptrs.data()), std::string("write the ") + what + " names");
}

std::vector<int> to_int(const std::vector<std::uint32_t>& v, std::int64_t offset) {
  std::vector<int> out(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) out[i] = int(std::int64_t(v[i]) + offset);
  return out;
}

}  // namespace

int exodus_side_number(const std::uint32_t* tet, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  return local_face_of(tet, kExodusSideInward, a, b, c) + 1;
}

void write_exodus(const FeMesh& mesh, const std::string& path) {
  const FeIndex index = index_fe_mesh(mesh, "write_exodus");
  const EntityTable& regions = index.dim[3];
  const std::size_t nt = mesh.num_tets(), tn = std::size_t(mesh.tet_nodes());
  check_fits(mesh.points.size(), "node count");
  check_fits(mesh.tets.size(), "connectivity length");
  check_fits(std::uint64_t(mesh.groups.size()) + 1, "group count");
  if (!regions.ids.empty()) check_fits(std::uint64_t(regions.ids.back()) + 1, "block id (region id + 1)");
  // Side sets first: a face no tet has fails before anything is created.
  const GroupFaceOwners owners = match_group_faces(mesh, index, kExodusSideInward, "write_exodus", "a side set");

  // Elements block by block; element number of tet t: exo_number[t] (1-based).
  std::vector<int> exo_number(nt), num_map;
  num_map.reserve(nt);
  for (std::size_t k = 0; k < regions.size(); ++k)
    for (std::size_t j = regions.start[k]; j < regions.start[k + 1]; ++j) {
      const std::uint32_t t = regions.element_of[j];
      num_map.push_back(int(t) + 1);
      exo_number[t] = int(num_map.size());
    }
  std::vector<std::string> block_names(regions.size());
  for (std::size_t k = 0; k < regions.size(); ++k) {
    block_names[k] = "region_" + std::to_string(regions.ids[k]);
    for (const FeGroup& g : mesh.groups)
      if (g.dim == 3 && !g.entities.empty() &&
          std::all_of(g.entities.begin(), g.entities.end(), [&](std::uint32_t e) { return e == regions.ids[k]; })) {
        block_names[k] = g.name;
        break;
      }
  }
  std::size_t num_side_sets = 0, longest = 0;
  for (const std::string& n : block_names) longest = std::max(longest, n.size());
  for (const FeGroup& g : mesh.groups) {
    num_side_sets += g.dim == 2;
    longest = std::max(longest, g.name.size());
  }

  AtomicFile file(path);
  const std::lock_guard<std::mutex> lock(exodus_mutex());
  ex_opts(EX_DEFAULT);  // neither abort nor print on errors: they become OutputErrors
  ExodusFile f(file.temp_path(), path);
  const int id = f.id();
  if (longest > 32) f.check(ex_set_max_name_length(id, int(longest)), "set the name length");
  f.check(ex_put_init(id, "kdmesh", 3, std::int64_t(mesh.points.size()), std::int64_t(nt),
                      std::int64_t(regions.size()), std::int64_t(mesh.groups.size()), std::int64_t(num_side_sets)),
          "write the header");

  const std::size_t np = mesh.points.size();
  std::vector<double> xyz[3];
  for (auto& c : xyz) c.resize(np);
  for (std::size_t n = 0; n < np; ++n)
    for (int c = 0; c < 3; ++c) xyz[c][n] = mesh.points.xyz[3 * n + std::size_t(c)];
  f.check(ex_put_coord(id, xyz[0].data(), xyz[1].data(), xyz[2].data()), "write the coordinates");
  char coord_names[3][2] = {"x", "y", "z"};
  char* coord_ptrs[3] = {coord_names[0], coord_names[1], coord_names[2]};
  f.check(ex_put_coord_names(id, coord_ptrs), "write the coordinate names");

  // "TETRA", not "TETRA4": meshio 5 maps TETRA4 to a cell type it does not know (KeyError)
  const char* type = mesh.order == 2 ? "TETRA10" : "TETRA";
  for (std::size_t k = 0; k < regions.size(); ++k) {
    const ex_entity_id block = ex_entity_id(regions.ids[k]) + 1;
    f.check(ex_put_block(id, EX_ELEM_BLOCK, block, type, std::int64_t(regions.num_elements(k)),
                         std::int64_t(tn), 0, 0, 0),
            "define element block " + std::to_string(block));
    std::vector<int> conn;
    conn.reserve(regions.num_elements(k) * tn);
    for (std::size_t j = regions.start[k]; j < regions.start[k + 1]; ++j) {
      const std::uint32_t* el = mesh.tets.data() + std::size_t(regions.element_of[j]) * tn;
      for (std::size_t i = 0; i < tn; ++i) conn.push_back(int(el[i]) + 1);
    }
    f.check(ex_put_conn(id, EX_ELEM_BLOCK, block, conn.data(), nullptr, nullptr),
            "write the connectivity of element block " + std::to_string(block));
  }
  put_names(f, EX_ELEM_BLOCK, block_names, "element block");
  if (!num_map.empty()) f.check(ex_put_id_map(id, EX_ELEM_MAP, num_map.data()), "write the element number map");

  std::vector<std::string> side_names, node_names;
  for (std::size_t g = 0; g < mesh.groups.size(); ++g) {
    const FeGroup& grp = mesh.groups[g];
    const ex_entity_id set = ex_entity_id(g) + 1;
    if (grp.dim == 2) {
      const EntityTable& ft = index.dim[2];
      std::vector<std::uint32_t> faces;
      for (const std::uint32_t e : grp.entities) {
        const std::size_t k = ft.find(e);
        faces.insert(faces.end(), ft.element_of.begin() + std::ptrdiff_t(ft.start[k]),
                     ft.element_of.begin() + std::ptrdiff_t(ft.start[k + 1]));
      }
      std::sort(faces.begin(), faces.end());
      faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
      std::vector<int> elems, sides;
      for (const std::uint32_t fc : faces) {
        const std::uint32_t slot = owners.slot_of_face[fc];
        elems.push_back(exo_number[owners.tet[slot]]);
        sides.push_back(int(owners.face[slot]) + 1);
      }
      f.check(ex_put_set_param(id, EX_SIDE_SET, set, std::int64_t(elems.size()), 0),
              "define side set " + std::to_string(set));
      f.check(ex_put_set(id, EX_SIDE_SET, set, elems.data(), sides.data()),
              "write side set " + std::to_string(set));
      side_names.push_back(grp.name);
    }
    const std::vector<int> nodes = to_int(group_nodes(mesh, index, g), 1);
    f.check(ex_put_set_param(id, EX_NODE_SET, set, std::int64_t(nodes.size()), 0),
            "define node set " + std::to_string(set));
    f.check(ex_put_set(id, EX_NODE_SET, set, nodes.data(), nullptr), "write node set " + std::to_string(set));
    node_names.push_back(grp.name);
  }
  put_names(f, EX_SIDE_SET, side_names, "side set");
  put_names(f, EX_NODE_SET, node_names, "node set");
  f.close();
  file.commit();
}

}  // namespace kdmesh
