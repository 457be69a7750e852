// kdmesh — several named solids meshed together (an assembly's bodies, each from its own
// file): their prepared surfaces joined into one, with the bodies kept apart and named.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <array>
#include <string>
#include <vector>

#include "core/surface_mesh.h"
#include "mesher/surface/surface_prepare.h"

namespace kdmesh {

/// One named solid of a job's `bodies` list: its surface, and where it came from (messages).
struct NamedSurface {
  std::string name;               ///< the body's (and its region's) name; unique in the job
  std::string input = "surface";  ///< a file path when read from one; never opened here
  SurfaceMesh surface;
};

/// Two bodies that touch or overlap: their surfaces meet (a shared face, edge or vertex, or
/// crossing facets), or one lies inside the other's material. Carries both bodies' indices and
/// names, a point where they meet (on both surfaces) or that lies in both solids, and the
/// offending facets (ids in the joined surface; facet_in_body gives each one's own id).
class BodyContactError : public SurfaceError {
 public:
  BodyContactError(const std::string& msg, std::vector<std::uint32_t> facets, std::array<std::uint32_t, 2> bodies,
                   std::array<std::string, 2> names, std::array<double, 3> where)
      : SurfaceError(msg, std::move(facets)), bodies_(bodies), names_(std::move(names)), where_(where) {}
  const std::array<std::uint32_t, 2>& bodies() const { return bodies_; }
  const std::array<std::string, 2>& names() const { return names_; }
  const std::array<double, 3>& where() const { return where_; }

 private:
  std::array<std::uint32_t, 2> bodies_;
  std::array<std::string, 2> names_;
  std::array<double, 3> where_;
};

/// Joins the bodies' prepared surfaces (each validated and oriented on its own by
/// prepare_surface, its messages naming its own file and facets) into one prepared surface
/// whose bodies are the named ones: body k (its region in the mesh) is all of parts[k]'s
/// solids, whatever their count. Contact is decided exactly (no tolerance): closed facets of
/// two bodies that intersect at all (CGAL's exact predicates, after a box filter).
///  - Bodies apart: facets, shells and points keep the parts' order. A body whose outer shell
///    lies in another's material (not in one of its voids) is a BodyContactError.
///  - Bodies that touch along faces: each pair in contact is imprinted with the other (CGAL
///    PMP corefinement), so that where they touch both have the same triangles. The result's
///    mesh is then the outer surface of their union, and its `interfaces` hold the facets
///    between two bodies (once each) and every body's own surface. A facet of one body inside
///    another's material, coinciding facets facing the same way (both solids on one side) and
///    a contact along an edge or at a point only where no other body fills around it (the
///    union's surface is then not 2-manifold) are BodyContactErrors naming both bodies and a
///    point.
/// `names` gives the bodies' names (names.size() == parts.size() >= 1). Throws UsageError
/// for a size mismatch, an empty name or a repeated one.
PreparedSurface join_bodies(std::vector<PreparedSurface> parts, const std::vector<std::string>& names,
                            const std::vector<std::string>& inputs);

/// The edges of the outer surface (point id pairs of surface.mesh) where an interface meets it
/// (an interface edge with other than two interface facets, or between interfaces of different
/// pairs of bodies): the rims of the interfaces, feature edges of the mesh. Empty without
/// interfaces.
std::vector<std::uint32_t> interface_rim_edges(const PreparedSurface& surface);

/// The interface edges inside the solid that are feature curves (point id pairs of
/// surface.interfaces.mesh): where interfaces of different pairs of bodies meet (walls crossing),
/// where an interface ends inside the solid, and where it bends by angle_deg or more. Node
/// placement samples them like the outer surface's feature edges. Empty without interfaces.
std::vector<std::uint32_t> interface_inner_edges(const PreparedSurface& surface, double angle_deg);

}  // namespace kdmesh
