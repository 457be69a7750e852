// kdmesh — XDMF 3 + HDF5 writer for FeMesh (FEniCSx / dolfinx, ParaView).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <filesystem>
#include <string>

#include "core/fe_mesh.h"

namespace kdmesh {

/// Writes `mesh` as an XDMF 3 file `path` (XML) and its heavy data as the HDF5 file
/// xdmf_hdf5_path(path) beside it, both atomically (temporary files, renamed into place only
/// when both are written; only regular files are ever replaced). Three grids, in the layout
/// dolfinx's XDMFFile writes and reads (tested with dolfinx 0.5.2):
///   Grid "mesh":        XDMFFile.read_mesh(name="mesh")
///     Topology  Tetrahedron (order 1) | Tetrahedron_10 (order 2, VTK node order, which is
///               FeMesh's and what dolfinx's XDMF reader expects)   /Mesh/mesh/topology  int64 T x n
///     Geometry  XYZ                                                /Mesh/mesh/geometry  float64 N x 3
///   Grid "cell_tags":   read_meshtags(mesh, name="cell_tags")
///     the mesh's topology (same dataset); values = each tet's region (tet_entity, the VTU's
///     `region`)                                                    /MeshTags/cell_tags/values   int32 T
///   Grid "facet_tags":  read_meshtags(mesh, name="facet_tags") (after
///     mesh.topology.create_connectivity(2, 3))
///     Triangle | Triangle_6: every boundary face of mesh.faces     /MeshTags/facet_tags/topology int64 F x n
///     values: the physical tag of the first group of dim 2 (in mesh.groups order) that lists
///     the face's patch, i.e. its position in mesh.groups + 1 (the MSH writer's physical tag);
///     0 when no group of dim 2 lists it. So a face in several groups gets the first one's tag
///     (list the most specific group first), and every boundary face is tagged. The group
///     names and tags are also listed in <Information Name="group" Value="<tag> <name>"/>
///     elements of that grid (dolfinx ignores them).     /MeshTags/facet_tags/values  int32 F
/// Node ids are 0-based point ids. The XML names the HDF5 file by its file name alone (it lies
/// in the same folder). Feature edges and groups of dim 1 and 3 are not written.
///
/// Throws UsageError for an invalid mesh (see index_fe_mesh), a region id above 2^31 - 1 (tags
/// are int32), or a path whose HDF5 file name equals it or contains ':' (XDMF's separator);
/// OutputError naming the path (the .xdmf or the .h5) if a file cannot be written.
void write_xdmf(const FeMesh& mesh, const std::string& path);

/// The HDF5 file beside the XDMF file `path`: its extension replaced by ".h5" ("a.xdmf" ->
/// "a.h5", "a" -> "a.h5"), as dolfinx derives it.
inline std::string xdmf_hdf5_path(const std::string& path) {
  return std::filesystem::path(path).replace_extension(".h5").string();
}

/// write_xdmf for callers that commit several outputs together (core/atomic_file.h): writes the
/// XML into the existing file `xml_file` and the data into the existing file `h5_file` (their
/// temporaries), the XML naming the HDF5 file as `h5_name` (a file name). OutputErrors name
/// xml_file or h5_file.
void write_xdmf_files(const FeMesh& mesh, const std::string& xml_file, const std::string& h5_file,
                      const std::string& h5_name);

}  // namespace kdmesh
