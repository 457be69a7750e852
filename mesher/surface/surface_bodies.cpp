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
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"

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

/// The lexicographically first pair of facets of two different bodies that intersect, or
/// {kNoFacet, kNoFacet}: independent of the order box_self_intersection_d reports pairs in.
std::pair<std::uint32_t, std::uint32_t> first_contact(const SurfaceMesh& m, const Ranges& r) {
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
  std::pair<std::uint32_t, std::uint32_t> best{kNoFacet, kNoFacet};
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), [&](const Box& a, const Box& b) {
    std::uint32_t f = a.info(), g = b.info();
    if (r.body(f) == r.body(g)) return;
    if (g < f) std::swap(f, g);
    if (std::make_pair(f, g) >= best) return;
    const std::uint32_t* u = m.tri(f);
    const std::uint32_t* w = m.tri(g);
    if (CGAL::do_intersect(K::Triangle_3(P(u[0]), P(u[1]), P(u[2])), K::Triangle_3(P(w[0]), P(w[1]), P(w[2]))))
      best = {f, g};
  });
  return best;
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

  // Surfaces that meet: touching or crossing.
  const auto [f, g] = first_contact(joined, r);
  if (f != kNoFacet) {
    const std::uint32_t a = r.body(f), b = r.body(g);
    const std::array<double, 3> at = contact_point(joined, f, g);
    throw BodyContactError("bodies '" + names[a] + "' and '" + names[b] + "' touch or overlap at " + coords(at) +
                               " (" + facet_name(f) + " and " + facet_name(g) +
                               " meet there): the bodies of a job must lie apart; conforming "
                               "interfaces between touching bodies are not supported yet",
                           {f, g}, {a, b}, {names[a], names[b]}, at);
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

}  // namespace kdmesh
