// kdmesh — validity of a volume mesh as an FE domain for its input surface.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "mesher/domain.h"
#include "mesher/volume/volume_mesh.h"

namespace kdmesh {

/// Every property measured, so a report can show the figures and not only pass/fail.
struct MeshCheck {
  std::size_t tets = 0, boundary_faces = 0;
  std::size_t nonpositive_tets = 0;      ///< exact orient3d <= 0
  std::size_t flat_tets = 0;             ///< positive but zero at rounding level: volume-length < 1e-9
  std::size_t outside_tets = 0;          ///< centroid not strictly inside the solid
  std::size_t offsurface_vertices = 0;   ///< boundary-face vertices farther than 1e-9*bbox from the surface
  std::size_t offsurface_faces = 0;      ///< boundary faces beyond the Hausdorff tolerance
  double max_hausdorff = 0;              ///< max over boundary faces of (distance / local h)
  std::size_t open_edges = 0;            ///< boundary edges with != 2 boundary faces
  std::size_t nonmanifold_vertices = 0;  ///< boundary vertices whose faces form > 1 fan
  double mesh_volume = 0, solid_volume = 0;
  /// The mesh's volume per region (index: VolumeMesh::tet_region id; one entry when the mesh
  /// has no regions), summed in the same pass as mesh_volume.
  std::vector<double> region_volume;
  /// Touching bodies (domain.regions): faces between two regions, tets whose centroid lies
  /// in another body than their region's (straddling an interface), interface-face vertices
  /// off the interfaces (> 1e-9 x bbox diagonal) and interface faces beyond the Hausdorff
  /// tolerance from them.
  std::size_t interface_faces = 0, straddling_tets = 0, offinterface_vertices = 0, offinterface_faces = 0;
  double max_interface_hausdorff = 0;    ///< max over interface faces of (distance / local h)
  double interface_seconds = 0;          ///< the interface faces' checks
  double volume_error = 0;               ///< |mesh - solid| / solid
  bool volume_off = false;               ///< volume_error beyond the tolerance
  std::vector<std::string> failures;     ///< one line per failed property, naming examples
  /// Where a finer size would help (3 coordinates per place): the centroids of the boundary
  /// faces beyond the distance tolerance and, when the volume is off, of the 2% of boundary
  /// faces farthest from the surface (relative to h).
  std::vector<double> refine_at;
  /// True when every failure is one that a finer size can cure (faces too far from the
  /// surface, volume error) and none is a defect of the mesh itself.
  bool only_sizing_failures() const;
  bool ok() const { return failures.empty(); }
};

struct MeshCheckOptions {
  double hausdorff_tolerance = 0.1;  ///< times the local target size
  double volume_tolerance = 0.005;   ///< relative
};

MeshCheck check_volume_mesh(const VolumeMesh& mesh, const Domain& domain,
                            const MeshCheckOptions& options = {});

}  // namespace kdmesh
