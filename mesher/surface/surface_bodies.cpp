// kdmesh — several named solids meshed together: joining their prepared surfaces.
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Contact between bodies is decided by exact predicates only: CGAL's box_self_intersection_d
// pairs facets of different bodies whose closed bounding boxes meet, and Epick's
// do_intersect(Triangle_3, Triangle_3) (orientation predicates, exact) decides each pair. The
// point named in the message is the exact intersection (Epeck), rounded once to doubles.
#include "mesher/surface/surface_bodies.h"

#include <CGAL/Box_intersection_d/Box_with_info_d.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "mesher/surface/surface_query.h"

namespace kdmesh {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using EK = CGAL::Exact_predicates_exact_constructions_kernel;
using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::uint32_t>;

std::string coords(const std::array<double, 3>& p) {
  std::ostringstream s;
  s.precision(9);
  s << "(" << p[0] << ", " << p[1] << ", " << p[2] << ")";
  return s.str();
}

/// Which body each facet of the joined surface belongs to, and each body's first facet.
struct Ranges {
  std::vector<std::uint32_t> facet_body;
  std::vector<std::uint32_t> first_facet;  ///< one per body, then the facet count
  std::uint32_t body(std::uint32_t f) const { return facet_body[f]; }
  std::uint32_t local(std::uint32_t f) const { return f - first_facet[facet_body[f]]; }
};

/// A point shared by two closed facets that intersect (exactly computed, then rounded).
std::array<double, 3> contact_point(const SurfaceMesh& m, std::uint32_t f, std::uint32_t g) {
  auto tri = [&](std::uint32_t t) {
    const std::uint32_t* v = m.tri(t);
    auto P = [&](int k) {
      const double* p = m.points.p(v[k]);
      return EK::Point_3(p[0], p[1], p[2]);
    };
    return EK::Triangle_3(P(0), P(1), P(2));
  };
  const auto x = CGAL::intersection(tri(f), tri(g));
  EK::Point_3 c = tri(f).vertex(0);  // not reached for an intersecting pair
  if (x) {
    if (const EK::Point_3* p = boost::get<EK::Point_3>(&*x)) c = *p;
    else if (const EK::Segment_3* s = boost::get<EK::Segment_3>(&*x)) c = CGAL::midpoint(s->source(), s->target());
    else if (const EK::Triangle_3* t = boost::get<EK::Triangle_3>(&*x)) c = CGAL::centroid(*t);
    else if (const auto* ps = boost::get<std::vector<EK::Point_3>>(&*x); ps && !ps->empty()) {
      EK::FT sx = 0, sy = 0, sz = 0;  // the polygon's vertex centroid: inside it (convex)
      for (const EK::Point_3& q : *ps) sx += q.x(), sy += q.y(), sz += q.z();
      const EK::FT n(int(ps->size()));
      c = EK::Point_3(sx / n, sy / n, sz / n);
    }
  }
  return {CGAL::to_double(c.x()), CGAL::to_double(c.y()), CGAL::to_double(c.z())};
}

/// For each pair of bodies whose closed facets intersect (touch or cross), the lexicographically
/// first such pair of facets: independent of the order box_self_intersection_d reports pairs in.
std::map<std::pair<std::uint32_t, std::uint32_t>, std::pair<std::uint32_t, std::uint32_t>> contacts(
    const SurfaceMesh& m, const Ranges& r) {
  std::vector<Box> boxes;
  boxes.reserve(m.num_tris());
  auto P = [&](std::uint32_t v) {
    const double* p = m.points.p(v);
    return K::Point_3(p[0], p[1], p[2]);
  };
  for (std::uint32_t f = 0; f < m.num_tris(); ++f) {
    const std::uint32_t* v = m.tri(f);
    boxes.emplace_back(P(v[0]).bbox() + P(v[1]).bbox() + P(v[2]).bbox(), f);
  }
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::pair<std::uint32_t, std::uint32_t>> found;
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), [&](const Box& a, const Box& b) {
    std::uint32_t f = a.info(), g = b.info();
    if (r.body(f) == r.body(g)) return;
    if (g < f) std::swap(f, g);
    const std::pair<std::uint32_t, std::uint32_t> bodies{r.body(f), r.body(g)};
    auto it = found.find(bodies);
    if (it != found.end() && std::make_pair(f, g) >= it->second) return;
    const std::uint32_t* u = m.tri(f);
    const std::uint32_t* w = m.tri(g);
    if (CGAL::do_intersect(K::Triangle_3(P(u[0]), P(u[1]), P(u[2])), K::Triangle_3(P(w[0]), P(w[1]), P(w[2]))))
      found[bodies] = {f, g};
  });
  return found;
}

/// A body whose surface lies apart from another's but inside its material (not in a void):
/// one vertex decides, exactly (ray parity). Throws BodyContactError.
void check_not_nested(const std::vector<PreparedSurface>& parts, const std::vector<SurfaceQuery*>& query,
                      std::uint32_t a, std::uint32_t b, const std::vector<std::string>& names,
                      const std::vector<std::string>& inputs) {
  for (const auto& [in, out] : {std::pair{b, a}, std::pair{a, b}}) {
    const SurfaceMesh& m = parts[in].mesh;
    if (m.num_tris() == 0) continue;
    const double* q = m.points.p(m.tri(0)[0]);
    if (query[out]->side(q) <= 0) continue;
    const std::array<double, 3> at{q[0], q[1], q[2]};
    throw BodyContactError("bodies '" + names[out] + "' and '" + names[in] + "' overlap: '" + names[in] +
                               "' lies inside the material of '" + names[out] + "' (e.g. its point " + coords(at) +
                               ", a corner of facet 0 of " + inputs[in] + "); the bodies of a job must not overlap",
                           {}, {out, in}, {names[out], names[in]}, at);
  }
}

// ---------------------------------------------------------------------------------------------
// Touching bodies: imprinting and the interfaces.
// Exact constructions: the points corefinement creates where edges of one body cross facets of
// the other lie exactly on both (with Epick, rounded intersection points off the facets' planes
// crashed CGAL 5.5's face triangulation on the gear box's coincident cylinders). They are
// rounded to doubles once, after the interfaces were found exactly.
using Mesh = CGAL::Surface_mesh<EK::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

Mesh to_cgal(const SurfaceMesh& s) {
  Mesh m;
  std::vector<Mesh::Vertex_index> v(s.points.size());
  for (std::uint32_t i = 0; i < s.points.size(); ++i) {
    const double* p = s.points.p(i);
    v[i] = m.add_vertex(EK::Point_3(p[0], p[1], p[2]));
  }
  for (std::size_t f = 0; f < s.num_tris(); ++f) m.add_face(v[s.tri(f)[0]], v[s.tri(f)[1]], v[s.tri(f)[2]]);
  return m;
}

/// The facets of a CGAL mesh as point triples, in face order.
std::vector<std::array<EK::Point_3, 3>> triangles(const Mesh& m) {
  std::vector<std::array<EK::Point_3, 3>> t;
  t.reserve(m.number_of_faces());
  for (Mesh::Face_index f : m.faces()) {
    std::array<EK::Point_3, 3> x;
    int k = 0;
    for (Mesh::Vertex_index v : CGAL::vertices_around_face(m.halfedge(f), m)) x[std::size_t(k++)] = m.point(v);
    t.push_back(x);
  }
  return t;
}

/// Exactly: triangle u lies in triangle w's plane and its centroid in w (closed).
bool lies_on(const std::array<EK::Point_3, 3>& u, const std::array<EK::Point_3, 3>& w) {
  for (const EK::Point_3& p : u)
    if (CGAL::orientation(w[0], w[1], w[2], p) != CGAL::COPLANAR) return false;
  return EK::Triangle_3(w[0], w[1], w[2]).has_on(CGAL::centroid(u[0], u[1], u[2]));
}

bool same_facing(const std::array<EK::Point_3, 3>& u, const std::array<EK::Point_3, 3>& w) {
  const EK::Vector_3 nu = CGAL::cross_product(u[1] - u[0], u[2] - u[0]);
  const EK::Vector_3 nw = CGAL::cross_product(w[1] - w[0], w[2] - w[0]);
  return CGAL::is_positive(nu * nw);
}

std::array<double, 3> rounded(const EK::Point_3& p) {
  return {CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())};
}

/// Two bodies whose surfaces meet, and a point where they do.
struct Contact {
  std::uint32_t a, b;
  std::array<double, 3> at;
};

struct Touching {
  std::vector<Mesh> mesh;                                  ///< imprinted, per body
  std::vector<std::vector<std::array<EK::Point_3, 3>>> tri; ///< their facets
  std::vector<std::vector<std::uint32_t>> on;              ///< per facet: the body it lies on, or kNoFacet
};

/// Marks the facets of bodies a and b that lie on the other's surface; facets of the two on
/// each other facing the same way (both solids on one side) are an overlap.
void mark_interface(Touching& t, std::uint32_t a, std::uint32_t b, const std::vector<std::string>& names) {
  std::vector<Box> ba, bb;
  for (std::uint32_t f = 0; f < t.tri[a].size(); ++f)
    ba.emplace_back(t.tri[a][f][0].bbox() + t.tri[a][f][1].bbox() + t.tri[a][f][2].bbox(), f);
  for (std::uint32_t g = 0; g < t.tri[b].size(); ++g)
    bb.emplace_back(t.tri[b][g][0].bbox() + t.tri[b][g][1].bbox() + t.tri[b][g][2].bbox(), g);
  std::pair<std::uint32_t, std::uint32_t> overlap{kNoFacet, kNoFacet};
  CGAL::box_intersection_d(ba.begin(), ba.end(), bb.begin(), bb.end(), [&](const Box& x, const Box& y) {
    const std::uint32_t f = x.info(), g = y.info();
    const auto &u = t.tri[a][f], &w = t.tri[b][g];
    const bool f_on = lies_on(u, w), g_on = lies_on(w, u);
    if (!f_on && !g_on) return;
    if (same_facing(u, w)) {
      overlap = std::min(overlap, std::make_pair(f, g));
      return;
    }
    if (f_on) t.on[a][f] = b;
    if (g_on) t.on[b][g] = a;
  });
  if (overlap.first != kNoFacet) {
    const std::array<double, 3> at =
        rounded(CGAL::centroid(t.tri[a][overlap.first][0], t.tri[a][overlap.first][1], t.tri[a][overlap.first][2]));
    throw BodyContactError("bodies '" + names[a] + "' and '" + names[b] + "' overlap: their surfaces coincide at " +
                               coords(at) + " facing the same way (both solids on one side)",
                           {}, {a, b}, {names[a], names[b]}, at);
  }
}

/// Vertex counts of a mesh: those it has (removed ones included: indices) and removed.
struct VertexMark {
  Mesh::size_type count = 0, removed = 0;
};
VertexMark mark_of(const Mesh& m) { return {m.num_vertices(), m.number_of_removed_vertices()}; }

/// Whether mesh m, since `since`, has a vertex on the closed surface `other` (exact), or lost
/// one (then, conservatively, true). Corefinement only subdivides: it adds vertices and never
/// moves the surfaces. Two meshes imprinted with each other conform along their contact, and
/// stay so while the imprints of third bodies add no vertex on it (a vertex off `other` comes
/// with edges inside faces that meet `other` at most along edges kept whole), so imprinting
/// the two again would change nothing.
bool added_on(const Mesh& m, VertexMark since, const Mesh& other) {
  if (m.number_of_removed_vertices() != since.removed) return true;
  std::vector<Box> added;
  for (Mesh::size_type i = since.count; i < m.num_vertices(); ++i)
    added.emplace_back(m.point(Mesh::Vertex_index(i)).bbox(), std::uint32_t(i));
  if (added.empty()) return false;
  const std::vector<std::array<EK::Point_3, 3>> tri = triangles(other);
  std::vector<Box> faces;
  faces.reserve(tri.size());
  for (std::uint32_t f = 0; f < tri.size(); ++f)
    faces.emplace_back(tri[f][0].bbox() + tri[f][1].bbox() + tri[f][2].bbox(), f);
  bool on = false;
  // Closed boxes (the default), each around its exact point or triangle: every vertex on a
  // triangle meets its box, and is then tested exactly.
  CGAL::box_intersection_d(added.begin(), added.end(), faces.begin(), faces.end(), [&](const Box& x, const Box& y) {
    const auto& t = tri[y.info()];
    on = on || EK::Triangle_3(t[0], t[1], t[2]).has_on(m.point(Mesh::Vertex_index(x.info())));
  });
  return on;
}

/// Bodies that touch: each pair in contact is imprinted with the other (CGAL PMP corefinement),
/// and again while the imprint of a third body adds a vertex on its contact; facets of one on
/// the other's surface are the interface between the two (kept once, from the body with the
/// lower id); the others make the outer surface of the union. A facet of one inside the
/// other's material is an overlap (BodyContactError), and so is a contact without a shared face
/// (along an edge or at a point only).
PreparedSurface join_touching(std::vector<PreparedSurface> parts, const std::vector<std::string>& names,
                              const std::vector<std::string>& inputs,
                              const std::vector<Contact>& pairs, const std::vector<SurfaceQuery*>& query) {
  const std::uint32_t nb = std::uint32_t(parts.size());
  Touching t;
  for (const PreparedSurface& p : parts) t.mesh.push_back(to_cgal(p.mesh));
  // Each pass imprints the pairs that may not conform: all at first, then those whose bodies
  // gained a vertex on their contact since (added_on). Imprinting a pair that conforms changes
  // nothing, but is not free: on the paper gear box the first pass took 0.14 s and a second
  // one over all five pairs, which changed nothing, 1.18 s (exact arithmetic on coincident
  // faces).
  std::vector<char> due(pairs.size(), 1);
  std::size_t imprints = 0;
  std::vector<std::pair<VertexMark, VertexMark>> after(pairs.size());  // each pair's last imprint
  for (int pass = 0;; ++pass) {
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      if (!due[k]) continue;
      const auto& [a, b, at] = pairs[k];
      try {
        PMP::corefine(t.mesh[a], t.mesh[b]);
      } catch (const std::exception& e) {
        throw GeometryError("bodies '" + names[a] + "' and '" + names[b] + "': imprinting their contact failed (" +
                            e.what() + ")");
      }
      after[k] = {mark_of(t.mesh[a]), mark_of(t.mesh[b])};
      ++imprints;
    }
    bool any = false;
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      const auto& [a, b, at] = pairs[k];
      due[k] = added_on(t.mesh[a], after[k].first, t.mesh[b]) || added_on(t.mesh[b], after[k].second, t.mesh[a]);
      any = any || due[k];
    }
    if (!any) break;
    if (pass == 8) throw GeometryError("imprinting the touching bodies did not settle after 8 passes");
  }
  for (const Mesh& m : t.mesh) {
    t.tri.push_back(triangles(m));
    t.on.emplace_back(t.tri.back().size(), kNoFacet);
  }
  for (const auto& [a, b, at] : pairs) mark_interface(t, a, b, names);
  // Facets off the other bodies' surfaces must lie outside their material.
  for (std::uint32_t a = 0; a < nb; ++a)
    for (std::uint32_t f = 0; f < t.tri[a].size(); ++f) {
      if (t.on[a][f] != kNoFacet) continue;
      const std::array<double, 3> c = rounded(CGAL::centroid(t.tri[a][f][0], t.tri[a][f][1], t.tri[a][f][2]));
      const double q[3] = {c[0], c[1], c[2]};
      for (const auto& [x, y, at] : pairs) {
        if (x != a && y != a) continue;
        const std::uint32_t b = x == a ? y : x;
        if (query[b]->side(q) <= 0) continue;
        const std::array<double, 3> where{q[0], q[1], q[2]};
        // An overlap as thin as rounding: faces meant to coincide whose coordinates differ.
        const double depth = query[b]->distance(q);
        const double* lo = parts[b].bbox_min;
        const double* hi = parts[b].bbox_max;
        const double diag = std::hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
        std::ostringstream hint;
        hint.precision(3);
        if (depth <= 1e-6 * diag)
          hint << " (only " << depth << " deep there: if they are meant to touch, their faces must have exactly "
               << "the same coordinates; export the parts from one tessellation, or snap their coordinates to "
               << "each other)";
        throw BodyContactError("bodies '" + names[a] + "' and '" + names[b] + "' overlap: part of the surface of '" +
                                   names[a] + "' (" + inputs[a] + ") lies inside the material of '" + names[b] +
                                   "' (e.g. at " + coords(where) + "; the surfaces cross at " + coords(at) + ")" +
                                   hint.str() + "; the bodies of a job may touch but not overlap",
                               {}, {a, b}, {names[a], names[b]}, at);
      }
    }
  std::vector<Contact> edge_only;  // contacts without a shared face
  for (const auto& [a, b, at] : pairs) {
    double area_a = 0, area_b = 0;
    for (std::uint32_t f = 0; f < t.tri[a].size(); ++f)
      if (t.on[a][f] == b) area_a += std::sqrt(CGAL::to_double(EK::Triangle_3(t.tri[a][f][0], t.tri[a][f][1], t.tri[a][f][2]).squared_area()));
    for (std::uint32_t g = 0; g < t.tri[b].size(); ++g)
      if (t.on[b][g] == a) area_b += std::sqrt(CGAL::to_double(EK::Triangle_3(t.tri[b][g][0], t.tri[b][g][1], t.tri[b][g][2]).squared_area()));
    if (area_a == 0 && area_b == 0) {  // along an edge or at a point: fine where other bodies fill around
      edge_only.push_back({a, b, at});
      continue;
    }
    if (!(std::abs(area_a - area_b) <= 1e-9 * std::max(area_a, area_b)))
      throw GeometryError("bodies '" + names[a] + "' and '" + names[b] + "': their interface has area " +
                          std::to_string(area_a) + " on one and " + std::to_string(area_b) +
                          " on the other after imprinting (internal error)");
  }

  // The outer surface and the interfaces, points welded by exact coordinates.
  SurfaceMesh outer;
  BodyInterfaces ifc;
  ifc.imprints = imprints;
  std::vector<std::uint32_t> outer_body;  // per outer facet
  std::map<std::array<double, 3>, std::uint32_t> outer_id, ifc_id;
  auto id_of = [](std::map<std::array<double, 3>, std::uint32_t>& ids, PointSet& pts, const EK::Point_3& p) {
    const std::array<double, 3> x = rounded(p);
    auto [it, fresh] = ids.emplace(x, std::uint32_t(pts.size()));
    if (fresh) pts.push_back(x[0], x[1], x[2]);
    return it->second;
  };
  for (std::uint32_t a = 0; a < nb; ++a)
    for (std::uint32_t f = 0; f < t.tri[a].size(); ++f) {
      const std::uint32_t b = t.on[a][f];
      if (b == kNoFacet) {
        for (const EK::Point_3& p : t.tri[a][f]) outer.tris.push_back(id_of(outer_id, outer.points, p));
        outer_body.push_back(a);
      } else if (a < b) {
        for (const EK::Point_3& p : t.tri[a][f]) ifc.mesh.tris.push_back(id_of(ifc_id, ifc.mesh.points, p));
        ifc.bodies.push_back({a, b});
      }
    }
  SurfaceOptions so;
  so.check_self_intersections = false;  // each body was checked; contacts are imprinted
  PreparedSurface out;
  try {
    out = prepare_surface(std::move(outer), "the outer surface of the touching bodies", so);
  } catch (const SurfaceError& e) {
    if (!edge_only.empty()) {  // the likely cause: bodies that meet along an edge or at a point only
      const Contact& c = edge_only.front();
      throw BodyContactError("bodies '" + names[c.a] + "' and '" + names[c.b] + "' touch at " + coords(c.at) +
                                 " only along an edge or at a point, with no face in common, and no other body "
                                 "fills around them: their union is not a solid with a 2-manifold surface (" +
                                 e.what() + "); move them apart or let them share a face",
                             e.facets(), {c.a, c.b}, {names[c.a], names[c.b]}, c.at);
    }
    throw SurfaceError(std::string(e.what()) + " (where bodies touch, their union must be a solid bounded by a "
                       "2-manifold surface)", e.facets(), e.defect());
  }
  for (std::uint32_t s = 0; s < out.shell_body.size(); ++s) {
    std::uint32_t f = 0;
    while (out.tri_shell[f] != s) ++f;
    out.shell_body[s] = outer_body[f];
  }
  out.num_bodies = nb;
  out.notices.clear();
  for (PreparedSurface& p : parts) ifc.body_surfaces.push_back(std::move(p.mesh));
  out.interfaces = std::move(ifc);
  return out;
}

}  // namespace

PreparedSurface join_bodies(std::vector<PreparedSurface> parts, const std::vector<std::string>& names,
                            const std::vector<std::string>& inputs) {
  if (parts.empty() || names.size() != parts.size() || inputs.size() != parts.size())
    throw UsageError("join_bodies: " + std::to_string(parts.size()) + " bodies, " +
                     std::to_string(names.size()) + " names and " + std::to_string(inputs.size()) +
                     " inputs (one each, at least one body)");
  std::set<std::string> seen;
  for (const std::string& n : names)
    if (n.empty() || !seen.insert(n).second)
      throw UsageError("join_bodies: body names must be non-empty and distinct ('" + n + "')");

  // The joined surface: the parts' points and facets one after the other.
  SurfaceMesh joined;
  Ranges r;
  for (std::uint32_t k = 0; k < parts.size(); ++k) {
    const SurfaceMesh& m = parts[k].mesh;
    const std::uint32_t off = std::uint32_t(joined.points.size());
    if (joined.points.size() + m.points.size() >= kNoFacet || joined.num_tris() + m.num_tris() >= kNoFacet)
      throw UsageError("join_bodies: more than 2^32 - 1 points or facets in all");
    r.first_facet.push_back(std::uint32_t(joined.num_tris()));
    joined.points.xyz.insert(joined.points.xyz.end(), m.points.xyz.begin(), m.points.xyz.end());
    for (std::uint32_t v : m.tris) joined.tris.push_back(v + off);
    r.facet_body.insert(r.facet_body.end(), m.num_tris(), k);
  }
  r.first_facet.push_back(std::uint32_t(joined.num_tris()));
  auto facet_name = [&](std::uint32_t f) {
    return "facet " + std::to_string(r.local(f)) + " of " + inputs[r.body(f)];
  };

  // Surfaces that meet: touching or crossing. Bodies in contact are imprinted and joined along
  // their interfaces; bodies apart keep their own surfaces.
  const auto found = contacts(joined, r);
  if (!found.empty()) {
    std::vector<std::unique_ptr<SurfaceQuery>> owned;
    std::vector<SurfaceQuery*> query;
    for (const PreparedSurface& p : parts) {
      owned.push_back(std::make_unique<SurfaceQuery>(p.mesh));
      query.push_back(owned.back().get());
    }
    std::vector<Contact> pairs;
    for (const auto& [bodies, facets] : found)
      pairs.push_back({bodies.first, bodies.second, contact_point(joined, facets.first, facets.second)});
    for (std::uint32_t a = 0; a < parts.size(); ++a)
      for (std::uint32_t b = a + 1; b < parts.size(); ++b)
        if (!found.count({a, b})) check_not_nested(parts, query, a, b, names, inputs);
    return join_touching(std::move(parts), names, inputs, pairs, query);
  }

  // Nesting across bodies (the surfaces are apart, so each shell lies wholly inside or outside
  // every other). Each part is oriented already; no self-intersection can remain.
  SurfaceOptions so;
  so.check_self_intersections = false;
  PreparedSurface out = prepare_surface(std::move(joined), "the bodies together", so);
  const std::size_t ns = out.shell_body.size();
  std::vector<std::uint32_t> shell_part(ns, kNoFacet);
  for (std::uint32_t t = 0; t < out.tri_shell.size(); ++t)
    if (shell_part[out.tri_shell[t]] == kNoFacet) shell_part[out.tri_shell[t]] = r.body(t);
  for (std::uint32_t s = 0; s < ns; ++s) {
    const std::uint32_t p = out.shell_parent[s];
    if (out.shell_volume[s] >= 0 || p == kNoFacet || shell_part[s] == shell_part[p]) continue;
    // s bounds a void by its depth, but belongs to another body than its enclosing shell: a
    // body in another's material.
    const std::uint32_t a = shell_part[p], b = shell_part[s];
    std::uint32_t t = 0;
    while (out.tri_shell[t] != s) ++t;
    const double* q = out.mesh.points.p(out.mesh.tri(t)[0]);
    const std::array<double, 3> at{q[0], q[1], q[2]};
    throw BodyContactError("bodies '" + names[a] + "' and '" + names[b] + "' overlap: '" + names[b] +
                               "' lies inside the material of '" + names[a] + "' (e.g. its point " +
                               coords(at) + ", a corner of " + facet_name(t) +
                               "); the bodies of a job must lie apart",
                           {t}, {a, b}, {names[a], names[b]}, at);
  }
  out.shell_body = std::move(shell_part);
  out.num_bodies = std::uint32_t(parts.size());
  out.notices.clear();  // the parts' own notices were reported when they were prepared
  return out;
}

namespace {

/// The interface edges that are feature curves (other than two interface facets, facets of
/// different pairs of bodies, or bent by angle_deg or more between two facets of one pair),
/// each as (interface point ids, outer point ids or kNoFacet where an edge is no outer edge).
struct InterfaceFeature {
  std::uint32_t a, b;            ///< interface mesh point ids
  std::uint32_t outer_a, outer_b;  ///< outer surface point ids, when the edge is an outer edge
};

std::vector<InterfaceFeature> interface_features(const PreparedSurface& surface, double angle_deg) {
  const BodyInterfaces& ifc = surface.interfaces;
  std::vector<InterfaceFeature> out;
  if (ifc.empty()) return out;
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> edge_facets;
  for (std::uint32_t f = 0; f < ifc.mesh.num_tris(); ++f)
    for (int j = 0; j < 3; ++j) {
      const std::uint32_t a = ifc.mesh.tri(f)[j], b = ifc.mesh.tri(f)[(j + 1) % 3];
      edge_facets[{std::min(a, b), std::max(a, b)}].push_back(f);
    }
  const SurfaceMesh& m = surface.mesh;
  std::map<std::array<double, 3>, std::uint32_t> outer_id;
  for (std::uint32_t i = 0; i < m.points.size(); ++i) {
    const double* p = m.points.p(i);
    outer_id.emplace(std::array<double, 3>{p[0], p[1], p[2]}, i);
  }
  std::set<std::pair<std::uint32_t, std::uint32_t>> outer_edges;
  for (std::size_t f = 0; f < m.num_tris(); ++f)
    for (int j = 0; j < 3; ++j) {
      const std::uint32_t a = m.tri(f)[j], b = m.tri(f)[(j + 1) % 3];
      outer_edges.insert({std::min(a, b), std::max(a, b)});
    }
  auto outer = [&](std::uint32_t v) {
    const double* p = ifc.mesh.points.p(v);
    auto it = outer_id.find({p[0], p[1], p[2]});
    return it == outer_id.end() ? kNoFacet : it->second;
  };
  auto normal = [&](std::uint32_t f) {
    const std::uint32_t* t = ifc.mesh.tri(f);
    const double *a = ifc.mesh.points.p(t[0]), *b = ifc.mesh.points.p(t[1]), *c = ifc.mesh.points.p(t[2]);
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    return std::array<double, 3>{u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
  };
  const double cos_limit = std::cos(angle_deg * 3.14159265358979323846 / 180);
  for (const auto& [e, fs] : edge_facets) {
    bool feature = fs.size() != 2;
    for (std::uint32_t f : fs) feature = feature || ifc.bodies[f] != ifc.bodies[fs[0]];
    if (!feature && angle_deg > 0 && angle_deg < 180) {
      const std::array<double, 3> n0 = normal(fs[0]), n1 = normal(fs[1]);
      const double d = n0[0] * n1[0] + n0[1] * n1[1] + n0[2] * n1[2];
      const double l = std::sqrt((n0[0] * n0[0] + n0[1] * n0[1] + n0[2] * n0[2]) *
                                 (n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2]));
      // The two facets of a manifold interface edge run it opposite ways: the deviation from
      // flat is the angle between their normals.
      feature = l > 0 && d <= cos_limit * l;
    }
    if (!feature) continue;
    std::uint32_t a = outer(e.first), b = outer(e.second);
    if (a == kNoFacet || b == kNoFacet || !outer_edges.count({std::min(a, b), std::max(a, b)})) a = b = kNoFacet;
    out.push_back({e.first, e.second, a, b});
  }
  return out;
}

}  // namespace

std::vector<std::uint32_t> interface_rim_edges(const PreparedSurface& surface) {
  std::vector<std::uint32_t> out;
  for (const InterfaceFeature& f : interface_features(surface, 0))
    if (f.outer_a != kNoFacet) out.insert(out.end(), {f.outer_a, f.outer_b});
  return out;
}

std::vector<std::uint32_t> interface_inner_edges(const PreparedSurface& surface, double angle_deg) {
  std::vector<std::uint32_t> out;
  for (const InterfaceFeature& f : interface_features(surface, angle_deg))
    if (f.outer_a == kNoFacet) out.insert(out.end(), {f.a, f.b});
  return out;
}

}  // namespace kdmesh
