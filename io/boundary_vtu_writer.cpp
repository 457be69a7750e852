// kdmesh — boundary VTU writer: FeMesh faces and feature edges with per-group cell data.
// SPDX-License-Identifier: AGPL-3.0-or-later
// A vtkUnstructuredGrid with dim / entity / group cell data, encoded by VTK's XML writer in
// memory and written atomically. VTK types never leave this file.
#include "io/boundary_vtu_writer.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkCommand.h>
#include <vtkDataCompressor.h>
#include <vtkDoubleArray.h>
#include <vtkExecutive.h>
#include <vtkFieldData.h>
#include <vtkIdTypeArray.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkSignedCharArray.h>
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnsignedIntArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/error.h"
#include "io/fe_mesh_index.h"
#include "io/file_io.h"

namespace kdmesh {

namespace {

constexpr const char* kWho = "write_boundary_vtu";

/// zlib level 1, as io/vtu_writer.cpp (measured there: higher levels buy ~3% for 3-4x time).
constexpr int kZlibLevel = 1;

/// Collects the text of every VTK error event of the objects it observes (as in
/// io/vtu_writer.cpp), so that failures become an OutputError instead of console output.
class ErrorCollector : public vtkCommand {
 public:
  static ErrorCollector* New() { return new ErrorCollector; }
  void Execute(vtkObject*, unsigned long, void* call_data) override {
    std::string msg = call_data ? static_cast<const char*>(call_data) : "unknown VTK error";
    if (const auto colon = msg.find("): "); colon != std::string::npos) msg.erase(0, colon + 3);
    while (!msg.empty() && (msg.back() == '\n' || msg.back() == ' ')) msg.pop_back();
    if (!messages.empty()) messages += "; ";
    messages += msg;
  }
  std::string messages;
};

/// The cell-data array name of each group of dim 1 or 2 (empty for dim 3), as the header says.
std::vector<std::string> group_array_names(const FeMesh& mesh) {
  std::vector<std::string> names(mesh.groups.size());
  for (std::size_t g = 0; g < mesh.groups.size(); ++g) {
    const FeGroup& grp = mesh.groups[g];
    if (grp.dim != 1 && grp.dim != 2) continue;
    bool clash = grp.name == "dim" || grp.name == "entity";
    for (const FeGroup& other : mesh.groups)
      if (other.dim != grp.dim && (other.dim == 1 || other.dim == 2) && other.name == grp.name) clash = true;
    names[g] = clash ? grp.name + ".d" + std::to_string(grp.dim) : grp.name;
  }
  return names;
}

/// The boundary of `mesh` as a vtkUnstructuredGrid (all data copied). `index` from index_fe_mesh.
vtkSmartPointer<vtkUnstructuredGrid> to_grid(const FeMesh& mesh, const FeIndex& index) {
  const std::size_t nf = mesh.num_faces(), ne = mesh.num_edges(), nc = nf + ne;
  const std::size_t fn = std::size_t(mesh.face_nodes()), en = std::size_t(mesh.edge_nodes());

  // Points used by a face or an edge, renumbered in ascending FeMesh id.
  constexpr std::uint32_t kUnused = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> local(mesh.points.size(), kUnused);
  for (const std::uint32_t v : mesh.faces) local[v] = 0;
  for (const std::uint32_t v : mesh.edges) local[v] = 0;
  vtkNew<vtkUnsignedIntArray> node_id;
  node_id->SetName("node_id");
  std::size_t np = 0;
  for (const std::uint32_t l : local) np += l != kUnused;
  node_id->SetNumberOfTuples(vtkIdType(np));
  vtkNew<vtkDoubleArray> coords;
  coords->SetNumberOfComponents(3);
  coords->SetNumberOfTuples(vtkIdType(np));
  {
    double* xyz = coords->GetPointer(0);
    unsigned int* ids = node_id->GetPointer(0);
    std::uint32_t k = 0;
    for (std::size_t i = 0; i < local.size(); ++i) {
      if (local[i] == kUnused) continue;
      local[i] = k;
      ids[k] = static_cast<unsigned int>(i);
      std::copy_n(mesh.points.xyz.data() + 3 * i, 3, xyz + 3 * std::size_t(k));
      ++k;
    }
  }
  vtkNew<vtkPoints> points;
  points->SetData(coords);

  // Cells: faces then edges, in offsets + connectivity form, with their types.
  vtkNew<vtkIdTypeArray> offsets, connectivity;
  offsets->SetNumberOfValues(vtkIdType(nc + 1));
  connectivity->SetNumberOfValues(vtkIdType(mesh.faces.size() + mesh.edges.size()));
  vtkIdType* off = offsets->GetPointer(0);
  for (std::size_t c = 0; c <= nf; ++c) off[c] = vtkIdType(c * fn);
  for (std::size_t c = 1; c <= ne; ++c) off[nf + c] = vtkIdType(nf * fn + c * en);
  vtkIdType* conn = connectivity->GetPointer(0);
  for (std::size_t i = 0; i < mesh.faces.size(); ++i) conn[i] = local[mesh.faces[i]];
  for (std::size_t i = 0; i < mesh.edges.size(); ++i) conn[mesh.faces.size() + i] = local[mesh.edges[i]];
  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, connectivity);
  vtkNew<vtkUnsignedCharArray> types;
  types->SetNumberOfValues(vtkIdType(nc));
  const unsigned char face_type = mesh.order == 2 ? VTK_QUADRATIC_TRIANGLE : VTK_TRIANGLE;
  const unsigned char edge_type = mesh.order == 2 ? VTK_QUADRATIC_EDGE : VTK_LINE;
  std::fill_n(types->GetPointer(0), nf, face_type);
  std::fill_n(types->GetPointer(0) + nf, ne, edge_type);

  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->SetPoints(points);
  grid->SetCells(types, cells);
  grid->GetPointData()->AddArray(node_id);

  vtkNew<vtkSignedCharArray> dim;
  dim->SetName("dim");
  dim->SetNumberOfValues(vtkIdType(nc));
  std::fill_n(dim->GetPointer(0), nf, static_cast<signed char>(2));
  std::fill_n(dim->GetPointer(0) + nf, ne, static_cast<signed char>(1));
  grid->GetCellData()->AddArray(dim);
  vtkNew<vtkUnsignedIntArray> entity;
  entity->SetName("entity");
  entity->SetNumberOfValues(vtkIdType(nc));
  std::copy(mesh.face_entity.begin(), mesh.face_entity.end(), entity->GetPointer(0));
  std::copy(mesh.edge_entity.begin(), mesh.edge_entity.end(), entity->GetPointer(0) + nf);
  grid->GetCellData()->AddArray(entity);

  // One 0/1 array per boundary group: the elements of its entities, through the entity table.
  const std::vector<std::string> names = group_array_names(mesh);
  for (std::size_t g = 0; g < mesh.groups.size(); ++g) {
    if (names[g].empty()) continue;
    const FeGroup& grp = mesh.groups[g];
    const EntityTable& t = index.dim[grp.dim];
    const std::size_t first = grp.dim == 2 ? 0 : nf;  // cell of element 0 of this dimension
    auto member = vtkSmartPointer<vtkSignedCharArray>::New();
    member->SetName(names[g].c_str());
    member->SetNumberOfValues(vtkIdType(nc));
    signed char* m = member->GetPointer(0);
    std::fill_n(m, nc, static_cast<signed char>(0));
    for (const std::uint32_t e : grp.entities) {
      const std::size_t k = t.find(e);  // index_fe_mesh guarantees k < t.size()
      for (std::size_t j = t.start[k]; j < t.start[k + 1]; ++j) m[first + t.element_of[j]] = 1;
    }
    grid->GetCellData()->AddArray(member);

    auto tag = vtkSmartPointer<vtkIntArray>::New();
    tag->SetName(names[g].c_str());
    tag->SetNumberOfValues(2);
    tag->SetValue(0, int(g + 1));
    tag->SetValue(1, grp.dim);
    grid->GetFieldData()->AddArray(tag);
  }
  return grid;
}

}  // namespace

void write_boundary_vtu(const FeMesh& mesh, const std::string& path) {
  const FeIndex index = index_fe_mesh(mesh, kWho);
  if (mesh.num_faces() == 0 && mesh.num_edges() == 0)
    throw UsageError(std::string(kWho) + ": the mesh has no boundary faces and no feature edges");
  if (mesh.groups.size() >= std::size_t(std::numeric_limits<int>::max()))
    throw UsageError(std::string(kWho) + ": too many groups (" + std::to_string(mesh.groups.size()) + ")");
  const vtkSmartPointer<vtkUnstructuredGrid> grid = to_grid(mesh, index);

  // Encoded in memory, then written by write_file_atomically (see io/vtu_writer.cpp: VTK 9.1's
  // own file error path is unsafe).
  vtkNew<ErrorCollector> errors;
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->AddObserver(vtkCommand::ErrorEvent, errors);
  writer->WriteToOutputStringOn();
  writer->SetInputData(grid);
  writer->SetDataModeToAppended();  // raw, as write_vtu (io/vtu_writer.cpp)
  writer->EncodeAppendedDataOff();
  writer->SetCompressorTypeToZLib();
  writer->SetCompressionLevel(kZlibLevel);
  writer->GetCompressor()->AddObserver(vtkCommand::ErrorEvent, errors);
  writer->SetHeaderTypeToUInt64();
  writer->SetIdTypeToInt64();
  vtkNew<ErrorCollector> pipeline_errors;  // the executive repeats writer errors: kept off the console
  writer->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, pipeline_errors);

  const int ok = writer->Write();
  if (!ok || writer->GetErrorCode() != 0 || !errors->messages.empty())
    throw OutputError(path, "VTK could not encode the boundary mesh: " +
                                (errors->messages.empty()
                                     ? "VTK error code " + std::to_string(writer->GetErrorCode())
                                     : errors->messages));
  write_file_atomically(path, writer->GetOutputString());
}

}  // namespace kdmesh
