// kdmesh — independent validity check of a volume mesh against its input surface.
// Everything is recomputed from mesh.tets, mesh.nodes and the surface; nothing of the mesher's
// own bookkeeping is trusted (mesh.boundary is only compared against the recomputed faces).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/quality/mesh_check.h"
#include "mesher/tet_quality.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>

#include "core/face_samples.h"
#include "core/timer.h"
#include "core/triangle_distance.h"
#include "mesher/bucket_scatter.h"
#include "core/parallel_collect.h"
#include "core/parallel_for.h"
#include "core/uninit_allocator.h"
#include "mesher/quality/centroid_sides.h"
#include "mesher/delaunay/predicates.h"

namespace kdmesh {

namespace {

constexpr std::size_t kShow = 5;  // examples named per failure

std::string xyz(const double* p) {
  std::ostringstream s;
  s.precision(9);
  s << "(" << p[0] << ", " << p[1] << ", " << p[2] << ")";
  return s.str();
}

/// Walks over items grouped by vertex id (vertex v's at [start[v], start[v + 1])) go in
/// kWalkChunks ranges of ids, at once: each range's results apart, joined in range order, are
/// those of one walk (the same on any thread count).
constexpr std::size_t kWalkChunks = 64;

/// The first id of range c (c <= kWalkChunks): the ranges hold about equal numbers of items.
/// (Equal numbers of ids would not: a face goes to its smallest id, so low ids hold most
/// faces; split by ids, the gear box's group sorts ran 86 % on one of two threads.)
std::size_t chunk_begin(const std::vector<std::size_t>& start, std::size_t c) {
  if (start.empty()) return 0;
  if (c >= kWalkChunks) return start.size() - 1;
  const std::size_t target = start.back() * c / kWalkChunks;
  return std::size_t(std::lower_bound(start.begin(), start.end() - 1, target) - start.begin());
}

/// The faces of all tets, grouped by their smallest vertex id (group v: start[v]..start[v+1]),
/// each group sorted by (the other two ids, tet): a face shared by two tets is two adjacent
/// records. 16 bytes a record (until 2026-11 a 28-byte record held all three sorted ids and
/// the outward triple: pinion.ply's 4.3M faces took 0.24 s to sort, more of it moving memory).
struct Faces {
  struct Rec {
    std::uint64_t rest;  ///< the two larger vertex ids, (middle << 32) | largest
    std::uint32_t k;     ///< 4 x tet + which face (kF)
  };
  static constexpr int kF[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};  // outward
  const std::vector<std::uint32_t>& tets;
  /// Written whole by the scatter (in parallel), so not zeroed first: that was a serial
  /// memset of 64 bytes per tet (the gear box: 1.5 GB).
  std::vector<Rec, UninitAllocator<Rec>> rec;
  std::vector<std::size_t> start;

  std::uint32_t tet(std::size_t i) const { return rec[i].k / 4; }
  /// Record i's face as its tet sees it, outward.
  std::array<std::uint32_t, 3> out(std::size_t i) const {
    const std::uint32_t* v = &tets[4 * std::size_t(tet(i))];
    const int* f = kF[rec[i].k % 4];
    return {v[f[0]], v[f[1]], v[f[2]]};
  }
  /// The groups are walked in kChunks ranges of smallest ids (chunk_begin).
  static constexpr std::size_t kChunks = kWalkChunks;
  std::size_t chunk_begin(std::size_t c) const { return kdmesh::chunk_begin(start, c); }
  /// Calls g(c, v, i, j) for each run [i, j) of records of one vertex set whose smallest id is
  /// v, v in range c; the ranges taken by free cores, each range's runs in order.
  template <class G>
  void each_group(G&& g) const {
    parallel_blocks(kChunks, 1, [&](std::size_t cb, std::size_t ce, unsigned) {
      for (std::size_t c = cb; c < ce; ++c)
        for (std::size_t v = chunk_begin(c), ve = chunk_begin(c + 1); v < ve; ++v)
          for (std::size_t i = start[v], j = i; i < start[v + 1]; i = j) {
            while (j < start[v + 1] && rec[j].rest == rec[i].rest) ++j;
            g(c, std::uint32_t(v), i, j);
          }
    });
  }
};

/// Appends the chunks' vectors to `out` in chunk order.
template <class T>
void join(std::vector<std::vector<T>>& parts, std::vector<T>& out) {
  std::size_t n = out.size();
  for (const auto& p : parts) n += p.size();
  out.reserve(n);
  for (auto& p : parts) {
    out.insert(out.end(), p.begin(), p.end());
    std::vector<T>().swap(p);
  }
}

/// Up to kShow examples of a failure, found by chunks: each chunk's count and first examples;
/// joined, the count and the first kShow examples of one walk.
struct Examples {
  std::vector<std::size_t> count = std::vector<std::size_t>(Faces::kChunks, 0);
  std::vector<std::vector<std::string>> text = std::vector<std::vector<std::string>>(Faces::kChunks);
  /// Counts one in chunk c; true if its example is wanted (then give it to add).
  bool wanted(std::size_t c) { return count[c]++ < kShow; }
  void add(std::size_t c, std::string s) { text[c].push_back(std::move(s)); }
  std::size_t total() const {
    std::size_t n = 0;
    for (std::size_t k : count) n += k;
    return n;
  }
  std::string joined() const {
    std::string out;
    std::size_t shown = 0;
    for (const auto& t : text)
      for (const std::string& s : t)
        if (shown++ < kShow) out += s;
    return out;
  }
};

// Parity of the permutation taking `a` to `b` (same vertex set): true if even.
bool same_cycle(const std::array<std::uint32_t, 3>& a, const std::array<std::uint32_t, 3>& b) {
  for (int r = 0; r < 3; ++r)
    if (a[0] == b[r] && a[1] == b[(r + 1) % 3] && a[2] == b[(r + 2) % 3]) return true;
  return false;
}

/// The 4 faces of every tet: a counting sort on the smallest vertex (bucket_scatter), then
/// each group sorted on its own (in parallel).
Faces sorted_faces(const std::vector<std::uint32_t>& tets, std::size_t np) {
  const std::size_t nt = tets.size() / 4;
  Faces faces{tets, std::vector<Faces::Rec, UninitAllocator<Faces::Rec>>(4 * nt), {}};
  auto sorted_ids = [&](std::size_t k) {  // face k % 4 of tet k / 4, ascending
    const std::uint32_t* v = &tets[4 * (k / 4)];
    const int* f = Faces::kF[k % 4];
    std::uint32_t a = v[f[0]], b = v[f[1]], c = v[f[2]];
    if (a > b) std::swap(a, b);
    if (b > c) std::swap(b, c);
    if (a > b) std::swap(a, b);
    return std::array<std::uint32_t, 3>{a, b, c};
  };
  faces.start = bucket_scatter(
      4 * nt, np, [&](std::size_t k) { return sorted_ids(k)[0]; },
      [&](std::size_t k, std::size_t at) {
        const auto id = sorted_ids(k);
        faces.rec[at] = {(std::uint64_t(id[1]) << 32) | id[2], std::uint32_t(k)};
      });
  parallel_for(Faces::kChunks, [&](std::size_t cb, std::size_t ce, unsigned) {
    for (std::size_t v = faces.chunk_begin(cb); v < faces.chunk_begin(ce); ++v)
      std::sort(faces.rec.begin() + std::ptrdiff_t(faces.start[v]), faces.rec.begin() + std::ptrdiff_t(faces.start[v + 1]),
                [](const Faces::Rec& a, const Faces::Rec& c) { return a.rest != c.rest ? a.rest < c.rest : a.k < c.k; });
  }, 1);
  return faces;
}

/// The largest of `distance` over 7 sample points of the triangle (centroid, edge midpoints,
/// and the midpoints between the centroid and the corners): the check's face-distance measure.
template <class Distance>
double worst_sample(const double* p0, const double* p1, const double* p2, const Distance& distance) {
  double worst = 0;
  for (int k = 0; k < 7; ++k) {
    double s[3];
    face_sample(p0, p1, p2, k, s);
    worst = std::max(worst, distance(s));
  }
  return worst;
}

}  // namespace

bool MeshCheck::only_sizing_failures() const {
  return !failures.empty() && nonpositive_tets == 0 && flat_tets == 0 && outside_tets == 0 &&
         offsurface_vertices == 0 && open_edges == 0 && nonmanifold_vertices == 0 && straddling_tets == 0 &&
         offinterface_vertices == 0 &&
         failures.size() == std::size_t(offsurface_faces > 0) + std::size_t(offinterface_faces > 0) +
                                std::size_t(volume_off);
}

namespace {

using Tri = std::array<std::uint32_t, 3>;

/// Every id names a point and the array holds whole tets; false (with the failure) if not.
bool ids_valid(const VolumeMesh& mesh, MeshCheck& c) {
  const std::size_t np = mesh.nodes.points.size();
  for (std::size_t k = 0; k < mesh.tets.size(); ++k)
    if (mesh.tets[k] >= np) {
      c.failures.push_back("tet " + std::to_string(k / 4) + " references point " +
                           std::to_string(mesh.tets[k]) + " of " + std::to_string(np));
      return false;
    }
  if (mesh.tets.size() % 4 != 0) {
    c.failures.push_back("tet array length " + std::to_string(mesh.tets.size()) + " is not a multiple of 4");
    return false;
  }
  if (mesh.tets.size() >= (std::size_t(1) << 32)) {  // bucket_scatter's limit on the faces
    c.failures.push_back("the mesh has " + std::to_string(mesh.tets.size() / 4) +
                         " tets; the check takes fewer than 2^30");
    return false;
  }
  return true;
}

/// Per tet: exact orientation, zero volume at rounding level, and volume (in total and per
/// region) in parallel; then the centroids' sides, one exact inside test per set of tets
/// whose centroids are joined by clear segments (`faces` give the neighbour pairs): inside the
/// solid and, with regions, in the body of the tet's region (RegionQuery::in_body).
void check_tets(const VolumeMesh& mesh, const Domain& domain, const Faces& faces, MeshCheck& c) {
  const PointSet& pts = mesh.nodes.points;
  const std::size_t nt = mesh.num_tets();
  std::vector<std::uint8_t> bad_orient(nt, 0);
  const RegionQuery* rq = domain.regions;
  const bool regions = mesh.tet_region.size() == nt;
  const std::size_t nr =
      regions && nt ? std::size_t(*std::max_element(mesh.tet_region.begin(), mesh.tet_region.end())) + 1 : 1;
  std::vector<double> vol_part(64, 0.0), region_part(64 * nr, 0.0);  // per part; per part and region
  parallel_for(nt, [&](std::size_t b, std::size_t e, unsigned w) {
    double vol = 0;
    std::vector<double> rv(nr, 0.0);
    for (std::size_t t = b; t < e; ++t) {
      const std::uint32_t* v = &mesh.tets[4 * t];
      const double *a = pts.p(v[0]), *bb = pts.p(v[1]), *cc = pts.p(v[2]), *d = pts.p(v[3]);
      if (pred::orient3d(a, bb, cc, d) <= 0) bad_orient[t] = 1;
      else if (volume_length(a, bb, cc, d) < kZeroVolumeLength) bad_orient[t] = 2;  // zero volume
      const double u[3] = {bb[0] - a[0], bb[1] - a[1], bb[2] - a[2]};
      const double x[3] = {cc[0] - a[0], cc[1] - a[1], cc[2] - a[2]};
      const double y[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
      const double tv = (u[0] * (x[1] * y[2] - x[2] * y[1]) + u[1] * (x[2] * y[0] - x[0] * y[2]) +
                         u[2] * (x[0] * y[1] - x[1] * y[0])) / 6;
      vol += tv;
      rv[regions ? mesh.tet_region[t] : 0] += tv;
    }
    vol_part[w] += vol;
    for (std::size_t r = 0; r < nr; ++r) region_part[w * nr + r] += rv[r];
  }, 1024, 64);
  // The pairs of tets sharing a face: counted per range, then written at each range's place
  // (one array, as large as the pairs; not a copy per range).
  std::vector<std::size_t> at(Faces::kChunks + 1, 0);
  faces.each_group([&](std::size_t k, std::uint32_t, std::size_t i, std::size_t j) { at[k + 1] += j - i == 2; });
  for (std::size_t k = 0; k < Faces::kChunks; ++k) at[k + 1] += at[k];
  std::vector<TetPair, UninitAllocator<TetPair>> pairs(at.back());
  faces.each_group([&](std::size_t k, std::uint32_t, std::size_t i, std::size_t j) {
    if (j - i == 2) pairs[at[k]++] = {faces.tet(i), faces.tet(i + 1)};
  });
  const std::vector<std::int8_t> side = rq && regions
                                            ? centroid_sides(pts, mesh.tets, pairs, domain.query, *rq, mesh.tet_region)
                                            : centroid_sides(pts, mesh.tets, pairs, domain.query);
  for (double v : vol_part) c.mesh_volume += v;
  c.region_volume.assign(nr, 0.0);
  for (std::size_t w = 0; w < 64; ++w)
    for (std::size_t r = 0; r < nr; ++r) c.region_volume[r] += region_part[w * nr + r];

  std::ostringstream o, s, f, x;
  for (std::size_t t = 0; t < nt; ++t) {
    if (bad_orient[t] == 1 && c.nonpositive_tets++ < kShow) o << " " << t;
    if (bad_orient[t] == 2 && c.flat_tets++ < kShow) f << " " << t;
    if (side[t] <= 0 && c.outside_tets++ < kShow) {
      const std::uint32_t* v = &mesh.tets[4 * t];
      double m[3];
      for (int k = 0; k < 3; ++k) m[k] = (pts.p(v[0])[k] + pts.p(v[1])[k] + pts.p(v[2])[k] + pts.p(v[3])[k]) / 4;
      s << " " << t << " at " << xyz(m);
    }
  }
  if (c.nonpositive_tets)
    c.failures.push_back(std::to_string(c.nonpositive_tets) + " tet(s) not positively oriented (exact orient3d <= 0), e.g. tet" + o.str());
  if (c.flat_tets)
    c.failures.push_back(std::to_string(c.flat_tets) + " tet(s) of zero volume at rounding level (volume-length ratio < 1e-9), e.g. tet" + f.str());
  if (c.outside_tets)
    c.failures.push_back(std::to_string(c.outside_tets) + " tet(s) with the centroid not strictly inside the solid, e.g. tet" + s.str());
  for (std::size_t t = 0; t < nt; ++t)
    if (side[t] == 2 && c.straddling_tets++ < kShow) x << " " << t << " (region " << mesh.tet_region[t] << ")";
  if (c.straddling_tets)
    c.failures.push_back(std::to_string(c.straddling_tets) +
                         " tet(s) whose centroid lies in another body than their region's (across an interface), e.g. tet" +
                         x.str());
}

/// The faces by matching: once = boundary (outward), twice = interior (the two tets must see
/// it in opposite orientations; between two regions: an interface face), more = an error.
/// The mesher's own boundary list must be exactly the boundary faces found.
std::pair<std::vector<Tri>, std::vector<Tri>> match_faces(const VolumeMesh& mesh, const Domain& domain,
                                                          const Faces& faces, MeshCheck& c) {
  const PointSet& pts = mesh.nodes.points;
  const bool regions = domain.regions && mesh.tet_region.size() == mesh.num_tets();
  std::vector<Tri> bnd, ifc;
  std::vector<std::vector<Tri>> bnd_part(Faces::kChunks), ifc_part(Faces::kChunks);
  Examples overfull, same_side;
  faces.each_group([&](std::size_t k, std::uint32_t v, std::size_t i, std::size_t j) {
    if (j - i == 1) {
      bnd_part[k].push_back(faces.out(i));
    } else if (j - i == 2) {
      if (regions && mesh.tet_region[faces.tet(i)] != mesh.tet_region[faces.tet(i + 1)])
        ifc_part[k].push_back(faces.out(i));
      if (same_cycle(faces.out(i), faces.out(i + 1)) && same_side.wanted(k))
        same_side.add(k, " tets " + std::to_string(faces.tet(i)) + "/" + std::to_string(faces.tet(i + 1)));
    } else if (overfull.wanted(k)) {
      overfull.add(k, " face " + xyz(pts.p(v)) + "-" + xyz(pts.p(std::uint32_t(faces.rec[i].rest >> 32))) + "-" +
                          xyz(pts.p(std::uint32_t(faces.rec[i].rest))) + " in " + std::to_string(j - i) + " tets");
    }
  });
  join(bnd_part, bnd);
  join(ifc_part, ifc);
  c.boundary_faces = bnd.size();
  if (overfull.total())
    c.failures.push_back(std::to_string(overfull.total()) + " face(s) shared by more than two tets, e.g." +
                         overfull.joined());
  if (same_side.total())
    c.failures.push_back(std::to_string(same_side.total()) +
                         " face(s) whose two tets lie on the same side (overlap), e.g." + same_side.joined());
  std::vector<Tri> a, b;
  for (Tri f : bnd) std::sort(f.begin(), f.end()), a.push_back(f);
  for (std::size_t k = 0; k + 2 < mesh.boundary.size(); k += 3) {
    Tri f = {mesh.boundary[k], mesh.boundary[k + 1], mesh.boundary[k + 2]};
    std::sort(f.begin(), f.end());
    b.push_back(f);
  }
  run_workers(2, [&](unsigned w) { std::sort((w ? b : a).begin(), (w ? b : a).end()); });
  if (a != b)
    c.failures.push_back("the mesh's boundary list (" + std::to_string(b.size()) +
                         " faces) differs from the faces found in its tets (" + std::to_string(a.size()) + ")");
  return {std::move(bnd), std::move(ifc)};
}

/// A point's distance to one facet bounds its distance to the surface from above. Where that
/// bound through the facet the node records is already within `on_surface`, the point passes
/// without a tree query; otherwise (and for every failure reported) the distance is the
/// tree's. A convex function's maximum over a triangle is at a corner, so a boundary face whose
/// three corners are that close to one facet is as close everywhere: planar parts, most of a
/// CAD model's boundary, need no query at all.
struct FacetBound {
  const SurfaceMesh& sm;
  const std::vector<std::uint32_t>& node_facet;
  double on_surface;

  double operator()(const double* x, std::uint32_t f) const {
    if (f >= sm.num_tris()) return std::numeric_limits<double>::infinity();
    const std::uint32_t* t = sm.tri(f);
    return triangle_distance(x, sm.points.p(t[0]), sm.points.p(t[1]), sm.points.p(t[2]));
  }
  std::uint32_t facet_of(std::uint32_t v) const { return v < node_facet.size() ? node_facet[v] : kNoFacet; }
};

/// Boundary vertices on the surface (within on_surface).
void check_boundary_vertices(const VolumeMesh& mesh, const Domain& domain, const std::vector<Tri>& bnd,
                             const FacetBound& bound, MeshCheck& c) {
  const PointSet& pts = mesh.nodes.points;
  // The faces' distinct vertices in id order: marked, then collected on all threads (ids are
  // valid: ids_valid). Sorting the faces' 3.3M corners took one core 0.15 s on the paper gear box.
  std::vector<std::uint8_t> on(pts.size(), 0);
  for (const Tri& f : bnd)
    for (const std::uint32_t v : f) on[v] = 1;
  const std::vector<std::uint32_t> bverts = parallel_collect(pts.size(), [&](std::size_t v) { return on[v] != 0; });
  std::vector<double> vdist(bverts.size());
  parallel_for(bverts.size(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t k = b; k < e; ++k) {
      const double* x = pts.p(bverts[k]);
      const double d = bound(x, bound.facet_of(bverts[k]));
      vdist[k] = d <= bound.on_surface ? d : domain.query.distance(x);
    }
  }, 256);
  std::ostringstream ex;
  for (std::size_t k = 0; k < bverts.size(); ++k)
    if (vdist[k] > bound.on_surface && c.offsurface_vertices++ < kShow)
      ex << " " << bverts[k] << " at " << xyz(pts.p(bverts[k])) << " (distance " << vdist[k] << ")";
  if (c.offsurface_vertices)
    c.failures.push_back(std::to_string(c.offsurface_vertices) +
                         " boundary vertex(es) off the surface (> 1e-9 x bbox diagonal), e.g." + ex.str());
}

/// Each boundary face's distance from the surface, in units of h at its centroid: the largest
/// over 7 samples (worst_sample), or the corners' bound through one facet (FacetBound).
std::vector<double> check_boundary_faces(const VolumeMesh& mesh, const Domain& domain, const std::vector<Tri>& bnd,
                                         const FacetBound& bound, const MeshCheckOptions& options, MeshCheck& c) {
  const PointSet& pts = mesh.nodes.points;
  std::vector<double> fdist(bnd.size());
  parallel_for(bnd.size(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t k = b; k < e; ++k) {
      const double *p0 = pts.p(bnd[k][0]), *p1 = pts.p(bnd[k][1]), *p2 = pts.p(bnd[k][2]);
      double cen[3];
      for (int q = 0; q < 3; ++q) cen[q] = (p0[q] + p1[q] + p2[q]) / 3;
      // All three corners within on_surface of one facet their nodes record: the whole face is.
      double d = std::numeric_limits<double>::infinity();
      for (int i = 0; i < 3 && !(d <= bound.on_surface); ++i) {
        const std::uint32_t f = bound.facet_of(bnd[k][i]);
        if (f == kNoFacet) continue;
        d = std::max({bound(p0, f), bound(p1, f), bound(p2, f)});
      }
      if (!(d <= bound.on_surface)) d = worst_sample(p0, p1, p2, [&](const double* x) { return domain.query.distance(x); });
      fdist[k] = d / domain.sizing(cen);
    }
  }, 256);
  std::ostringstream ex;
  for (std::size_t k = 0; k < bnd.size(); ++k) {
    c.max_hausdorff = std::max(c.max_hausdorff, fdist[k]);
    if (fdist[k] > options.hausdorff_tolerance && c.offsurface_faces++ < kShow) {
      double cen[3];
      for (int q = 0; q < 3; ++q) cen[q] = (pts.p(bnd[k][0])[q] + pts.p(bnd[k][1])[q] + pts.p(bnd[k][2])[q]) / 3;
      ex << " face at " << xyz(cen) << " (" << fdist[k] << " h)";
    }
  }
  if (c.offsurface_faces)
    c.failures.push_back(std::to_string(c.offsurface_faces) + " boundary face(s) farther than " +
                         std::to_string(options.hausdorff_tolerance) + " h from the surface, e.g." + ex.str());
  return fdist;
}

/// Items grouped by a vertex id, each with a value: the values of vertex v's items are
/// value[start[v] .. start[v + 1]), in item order (a stable counting sort on all threads; a
/// sort of the paper gear box's 3.3M pairs took one core 0.3 s, twice).
struct ByVertex {
  std::vector<std::size_t> start;
  std::vector<std::uint32_t, UninitAllocator<std::uint32_t>> value;

  template <class VertexOf, class ValueOf>
  ByVertex(std::size_t np, std::size_t n, VertexOf&& vertex_of, ValueOf&& value_of) : value(n) {
    start = bucket_scatter(n, np, vertex_of, [&](std::size_t i, std::size_t at) { value[at] = value_of(i); });
  }
  /// Calls g(c, v, w) for every vertex v of range c, the kWalkChunks ranges (of about equal
  /// numbers of items) taken by free cores, each range's vertices in order; w < available_cpus()
  /// names the worker (for its scratch space).
  template <class G>
  void each_vertex(G&& g) const {
    parallel_blocks(kWalkChunks, 1, [&](std::size_t cb, std::size_t ce, unsigned w) {
      for (std::size_t c = cb; c < ce; ++c)
        for (std::size_t v = chunk_begin(start, c), ve = chunk_begin(start, c + 1); v < ve; ++v)
          g(c, std::uint32_t(v), w);
    });
  }
};

/// Boundary edges in exactly two boundary faces. Each edge (a < b) goes to a; a vertex's b's
/// sorted give the edges in (a, b) order, the order of a sort of them all.
void check_open_edges(const PointSet& pts, const std::vector<Tri>& bnd, MeshCheck& c) {
  auto ends = [&](std::size_t i) { return std::minmax(bnd[i / 3][i % 3], bnd[i / 3][(i + 1) % 3]); };
  const ByVertex edges(pts.size(), 3 * bnd.size(), [&](std::size_t i) { return ends(i).first; },
                       [&](std::size_t i) { return ends(i).second; });
  Examples ex;
  std::vector<std::vector<std::uint32_t>> scratch(available_cpus());
  edges.each_vertex([&](std::size_t ch, std::uint32_t a, unsigned w) {
    const std::size_t i0 = edges.start[a], i1 = edges.start[a + 1];
    if (i0 == i1) return;
    std::vector<std::uint32_t>& b = scratch[w];
    b.assign(edges.value.begin() + std::ptrdiff_t(i0), edges.value.begin() + std::ptrdiff_t(i1));
    std::sort(b.begin(), b.end());
    for (std::size_t i = 0, j = 0; i < b.size(); i = j) {
      while (j < b.size() && b[j] == b[i]) ++j;
      if (j - i != 2 && ex.wanted(ch)) {
        std::ostringstream e;
        e << " " << xyz(pts.p(a)) << "-" << xyz(pts.p(b[i])) << " in " << (j - i) << " face(s)";
        ex.add(ch, e.str());
      }
    }
  });
  c.open_edges = ex.total();
  if (c.open_edges)
    c.failures.push_back(std::to_string(c.open_edges) + " boundary edge(s) not in exactly two boundary faces, e.g." +
                         ex.joined());
}

/// Manifold boundary vertices: a vertex's faces form one fan iff they are connected through
/// edges at the vertex.
void check_vertex_fans(const PointSet& pts, const std::vector<Tri>& bnd, MeshCheck& c) {
  const ByVertex faces(pts.size(), 3 * bnd.size(), [&](std::size_t i) { return bnd[i / 3][i % 3]; },
                       [&](std::size_t i) { return std::uint32_t(i / 3); });
  Examples ex;
  std::vector<std::vector<int>> labels(available_cpus());
  faces.each_vertex([&](std::size_t ch, std::uint32_t v, unsigned w) {
    const std::size_t i = faces.start[v], m = faces.start[v + 1] - i;
    if (m == 0) return;
    std::vector<int>& label = labels[w];
    label.assign(m, -1);
    int fans = 0;
    for (std::size_t s = 0; s < m; ++s) {
      if (label[s] >= 0) continue;
      label[s] = fans;
      for (bool grew = true; grew;) {  // naive closure: m is small
        grew = false;
        for (std::size_t x = 0; x < m; ++x) {
          if (label[x] != fans) continue;
          for (std::size_t y = 0; y < m; ++y) {
            if (label[y] >= 0) continue;
            const auto& fx = bnd[faces.value[i + x]];
            const auto& fy = bnd[faces.value[i + y]];
            int shared = 0;  // vertices other than v in common
            for (auto p : fx)
              for (auto q : fy) shared += (p == q && p != v);
            if (shared > 0) label[y] = fans, grew = true;
          }
        }
      }
      ++fans;
    }
    if (fans > 1 && ex.wanted(ch)) {
      std::ostringstream e;
      e << " " << v << " at " << xyz(pts.p(v)) << " (" << fans << " fans)";
      ex.add(ch, e.str());
    }
  });
  c.nonmanifold_vertices = ex.total();
  if (c.nonmanifold_vertices)
    c.failures.push_back(std::to_string(c.nonmanifold_vertices) + " non-manifold boundary vertex(es), e.g." +
                         ex.joined());
}

/// Interfaces between touching bodies: their faces' vertices on them, their faces within the
/// tolerance (7 samples); the centroids of the faces beyond it go to refine_at.
void check_interfaces(const VolumeMesh& mesh, const Domain& domain, const std::vector<Tri>& ifc, double on_surface,
                      const MeshCheckOptions& options, MeshCheck& c) {
  const PointSet& pts = mesh.nodes.points;
  const RegionQuery* rq = domain.regions;
  Stopwatch interface_clock;
  c.interface_faces = ifc.size();
  if (rq && !ifc.empty()) {
    std::vector<std::uint32_t> iverts;
    for (auto& f : ifc) iverts.insert(iverts.end(), f.begin(), f.end());
    std::sort(iverts.begin(), iverts.end());
    iverts.erase(std::unique(iverts.begin(), iverts.end()), iverts.end());
    std::ostringstream vx;
    for (std::uint32_t v : iverts) {
      const double d = rq->interfaces().distance(pts.p(v));
      if (d > on_surface && c.offinterface_vertices++ < kShow)
        vx << " " << v << " at " << xyz(pts.p(v)) << " (distance " << d << ")";
    }
    if (c.offinterface_vertices)
      c.failures.push_back(std::to_string(c.offinterface_vertices) +
                           " interface vertex(es) off the interfaces (> 1e-9 x bbox diagonal), e.g." + vx.str());
    std::vector<double> idist(ifc.size());
    parallel_for(ifc.size(), [&](std::size_t b, std::size_t e, unsigned) {
      for (std::size_t k = b; k < e; ++k) {
        const double *p0 = pts.p(ifc[k][0]), *p1 = pts.p(ifc[k][1]), *p2 = pts.p(ifc[k][2]);
        double cen[3];
        for (int q = 0; q < 3; ++q) cen[q] = (p0[q] + p1[q] + p2[q]) / 3;
        const double worst = worst_sample(p0, p1, p2, [&](const double* x) { return rq->interfaces().distance(x); });
        idist[k] = worst / domain.sizing(cen);
      }
    }, 256);
    std::ostringstream ex;
    for (std::size_t k = 0; k < ifc.size(); ++k) {
      c.max_interface_hausdorff = std::max(c.max_interface_hausdorff, idist[k]);
      if (idist[k] > options.hausdorff_tolerance) {
        double cen[3];
        for (int q = 0; q < 3; ++q) cen[q] = (pts.p(ifc[k][0])[q] + pts.p(ifc[k][1])[q] + pts.p(ifc[k][2])[q]) / 3;
        c.refine_at.insert(c.refine_at.end(), cen, cen + 3);
        if (c.offinterface_faces++ < kShow) ex << " face at " << xyz(cen) << " (" << idist[k] << " h)";
      }
    }
    if (c.offinterface_faces)
      c.failures.push_back(std::to_string(c.offinterface_faces) + " interface face(s) farther than " +
                           std::to_string(options.hausdorff_tolerance) + " h from the interfaces, e.g." + ex.str());
  }
  c.interface_seconds = interface_clock.seconds();
}

/// The volume against the solid's; where a finer size would help: the boundary faces beyond
/// the tolerance and, when the volume is off, the 2% farthest from the surface (relative to h).
void check_volume(const VolumeMesh& mesh, const Domain& domain, const std::vector<Tri>& bnd,
                  const std::vector<double>& fdist, const MeshCheckOptions& options, MeshCheck& c) {
  const PointSet& pts = mesh.nodes.points;
  const double solid = domain.surface.volume;
  c.volume_error = solid != 0 ? std::fabs(c.mesh_volume - solid) / std::fabs(solid) : std::fabs(c.mesh_volume);
  auto add_refine = [&](std::size_t k) {
    for (int q = 0; q < 3; ++q)
      c.refine_at.push_back((pts.p(bnd[k][0])[q] + pts.p(bnd[k][1])[q] + pts.p(bnd[k][2])[q]) / 3);
  };
  for (std::size_t k = 0; k < bnd.size(); ++k)
    if (fdist[k] > options.hausdorff_tolerance) add_refine(k);
  c.volume_off = !(c.volume_error <= options.volume_tolerance);
  if (c.volume_off && !bnd.empty()) {
    std::vector<std::uint32_t> order(bnd.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = std::uint32_t(k);
    const std::size_t top = std::max<std::size_t>(1, bnd.size() / 50);
    std::partial_sort(order.begin(), order.begin() + std::ptrdiff_t(top), order.end(),
                      [&](std::uint32_t a, std::uint32_t b) { return fdist[a] != fdist[b] ? fdist[a] > fdist[b] : a < b; });
    for (std::size_t k = 0; k < top; ++k)
      if (!(fdist[order[k]] > options.hausdorff_tolerance)) add_refine(order[k]);
  }
  if (c.volume_off) {
    std::ostringstream s;
    s << "mesh volume " << c.mesh_volume << " differs from the solid's " << solid << " by "
      << c.volume_error * 100 << "% (tolerance " << options.volume_tolerance * 100 << "%)";
    c.failures.push_back(s.str());
  }
}

}  // namespace

MeshCheck check_volume_mesh(const VolumeMesh& mesh, const Domain& domain, const MeshCheckOptions& options) {
  MeshCheck c;
  c.tets = mesh.num_tets();
  c.solid_volume = domain.surface.volume;
  if (!ids_valid(mesh, c)) return c;
  const PointSet& pts = mesh.nodes.points;
  // The faces, sorted by their vertex sets: matched below; the inside test uses the pairs.
  const Faces faces = sorted_faces(mesh.tets, pts.size());
  check_tets(mesh, domain, faces, c);
  const auto [bnd, ifc] = match_faces(mesh, domain, faces, c);
  double diag = 0;
  for (int k = 0; k < 3; ++k) {
    const double e = domain.surface.bbox_max[k] - domain.surface.bbox_min[k];
    diag += e * e;
  }
  const FacetBound bound{domain.surface.mesh, mesh.nodes.facet, kOnSurfaceDistance * std::sqrt(diag)};
  check_boundary_vertices(mesh, domain, bnd, bound, c);
  const std::vector<double> fdist = check_boundary_faces(mesh, domain, bnd, bound, options, c);
  {  // independent walks over the boundary faces, on two threads; failures in this order
    MeshCheck fans;
    const std::vector<Tri>& faces_out = bnd;  // (clang 14 cannot capture a structured binding)
    run_workers(2, [&](unsigned w) {
      w == 0 ? check_open_edges(pts, faces_out, c) : check_vertex_fans(pts, faces_out, fans);
    });
    c.nonmanifold_vertices = fans.nonmanifold_vertices;
    c.failures.insert(c.failures.end(), fans.failures.begin(), fans.failures.end());
  }
  check_interfaces(mesh, domain, ifc, bound.on_surface, options, c);
  check_volume(mesh, domain, bnd, fdist, options, c);
  if (c.tets == 0) c.failures.push_back("the mesh has no tets");
  return c;
}

}  // namespace kdmesh
