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
/// solids, whatever their count; facets, shells and points keep the parts' order. Contact
/// is decided exactly (no tolerance): closed facets of two bodies that intersect at all
/// (CGAL's exact predicates, after a box filter) are a BodyContactError naming the first such
/// pair and a point they share; so is a body whose outer shell lies in another's material
/// (not in one of its voids). A body inside another's void is apart, and kept.
/// `names` gives the bodies' names (names.size() == parts.size() >= 1). Throws UsageError
/// for a size mismatch, an empty name or a repeated one.
PreparedSurface join_bodies(std::vector<PreparedSurface> parts, const std::vector<std::string>& names,
                            const std::vector<std::string>& inputs);

}  // namespace kdmesh
