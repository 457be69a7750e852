// kdmesh — tetrahedron shape measures (dihedral angles, radius ratio, radius-edge ratio,
// volume-length ratio) and their mesh-wide summaries.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/tet_quality.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/parallel_for.h"

namespace kdmesh {

namespace {
struct V3 {
  double x, y, z;
};
V3 sub(const double* a, const double* b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
double norm(V3 a) { return std::sqrt(dot(a, a)); }
constexpr double kPi = 3.14159265358979323846;

void add_to(Histogram& h, double value) {
  const std::size_t bins = h.counts.size();
  double f = (value - h.lo) / (h.hi - h.lo) * double(bins);
  std::size_t b = 0;
  if (f >= double(bins)) b = bins - 1;
  else if (f > 0) b = std::size_t(f);
  ++h.counts[b];
}
}  // namespace

// Conventions: the tet (a,b,c,d) is positive when det[b-a, c-a, d-a] > 0 (core/tet_mesh.h).
// Outward face normals of a positive tet: opposite a (b,c,d), opposite b (a,d,c),
// opposite c (a,b,d), opposite d (a,c,b). The interior dihedral angle along the edge shared
// by faces k and l is pi - angle(n_k, n_l). For an inverted tet the same formulas give the
// angles of its mirror image's complement; they are reported as computed (volume < 0 flags it).
double volume_length(const double* a, const double* b, const double* c, const double* d) {
  const double* p[4] = {a, b, c, d};
  const double det = dot(sub(b, a), cross(sub(c, a), sub(d, a)));  // 6 V
  double l2_sum = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) {
      const V3 e = sub(p[j], p[i]);
      l2_sum += dot(e, e);
    }
  const double l_rms = std::sqrt(l2_sum / 6);
  return l_rms > 0 ? std::sqrt(2.0) * det / (l_rms * l_rms * l_rms) : 0;
}

TetQuality tet_quality(const double* a, const double* b, const double* c, const double* d) {
  TetQuality q;
  const double* p[4] = {a, b, c, d};
  const V3 e1 = sub(b, a), e2 = sub(c, a), e3 = sub(d, a);
  const double det = dot(e1, cross(e2, e3));  // 6 V
  q.volume = det / 6;

  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  V3 n[4];
  double area2[4], area_sum = 0;
  for (int f = 0; f < 4; ++f) {
    n[f] = cross(sub(p[kFace[f][1]], p[kFace[f][0]]), sub(p[kFace[f][2]], p[kFace[f][0]]));
    area2[f] = norm(n[f]);  // twice the face area
    area_sum += area2[f] / 2;
  }
  // The angle falls as its cosine rises: the extreme angles are those of the extreme cosines,
  // two arc cosines per tet rather than six.
  double max_cos = -1, min_cos = 1;
  for (int k = 0; k < 4; ++k)
    for (int l = k + 1; l < 4; ++l) {
      // A face of zero area: the tet is flat there (angle 0, cosine 1).
      const double cosang = area2[k] == 0 || area2[l] == 0
                                ? 1.0
                                : std::clamp(-dot(n[k], n[l]) / (area2[k] * area2[l]), -1.0, 1.0);
      max_cos = std::max(max_cos, cosang);
      min_cos = std::min(min_cos, cosang);
    }
  q.min_dihedral = std::acos(max_cos) * 180 / kPi;
  q.max_dihedral = std::acos(min_cos) * 180 / kPi;

  // Edge lengths.
  double l2_min = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) {
      const V3 e = sub(p[j], p[i]);
      l2_min = std::min(l2_min, dot(e, e));
    }
  q.volume_length = volume_length(a, b, c, d);

  // Circumcentre offset from a: (|e1|^2 e2xe3 + |e2|^2 e3xe1 + |e3|^2 e1xe2) / (2 det).
  if (det == 0) {
    q.radius_ratio = 0;
    q.radius_edge = std::numeric_limits<double>::infinity();
    return q;
  }
  const V3 c23 = cross(e2, e3), c31 = cross(e3, e1), c12 = cross(e1, e2);
  const double s1 = dot(e1, e1), s2 = dot(e2, e2), s3 = dot(e3, e3);
  const V3 off = {(s1 * c23.x + s2 * c31.x + s3 * c12.x) / (2 * det),
                  (s1 * c23.y + s2 * c31.y + s3 * c12.y) / (2 * det),
                  (s1 * c23.z + s2 * c31.z + s3 * c12.z) / (2 * det)};
  const double R = norm(off);
  const double r_in = 3 * q.volume / area_sum;  // signed like the volume
  q.radius_ratio = 3 * r_in / R;
  q.radius_edge = l2_min > 0 ? R / std::sqrt(l2_min) : std::numeric_limits<double>::infinity();
  return q;
}

namespace {

/// The summary of a block of tets, before the means.
struct Partial {
  QualitySummary s;
  double sum_rr = 0, sum_vl = 0;
};

Partial empty_partial() {
  Partial p;
  p.s.min_dihedral_hist = {0, 90, std::vector<std::uint64_t>(18, 0)};
  p.s.radius_ratio_hist = {0, 1, std::vector<std::uint64_t>(10, 0)};
  p.s.min_dihedral = 180;
  p.s.max_dihedral = 0;
  p.s.min_radius_ratio = std::numeric_limits<double>::infinity();
  p.s.min_volume_length = std::numeric_limits<double>::infinity();
  return p;
}

void add_tet(Partial& p, const TetQuality& t) {
  QualitySummary& s = p.s;
  if (t.volume <= 0) ++s.inverted;
  s.min_dihedral = std::min(s.min_dihedral, t.min_dihedral);
  s.max_dihedral = std::max(s.max_dihedral, t.max_dihedral);
  s.min_radius_ratio = std::min(s.min_radius_ratio, t.radius_ratio);
  s.max_radius_edge = std::max(s.max_radius_edge, t.radius_edge);
  s.min_volume_length = std::min(s.min_volume_length, t.volume_length);
  p.sum_rr += t.radius_ratio;
  p.sum_vl += t.volume_length;
  add_to(s.min_dihedral_hist, t.min_dihedral);
  add_to(s.radius_ratio_hist, t.radius_ratio);
}

void merge(Partial& into, const Partial& p) {
  QualitySummary &s = into.s;
  const QualitySummary& o = p.s;
  s.inverted += o.inverted;
  s.min_dihedral = std::min(s.min_dihedral, o.min_dihedral);
  s.max_dihedral = std::max(s.max_dihedral, o.max_dihedral);
  s.min_radius_ratio = std::min(s.min_radius_ratio, o.min_radius_ratio);
  s.max_radius_edge = std::max(s.max_radius_edge, o.max_radius_edge);
  s.min_volume_length = std::min(s.min_volume_length, o.min_volume_length);
  into.sum_rr += p.sum_rr;
  into.sum_vl += p.sum_vl;
  for (std::size_t b = 0; b < s.min_dihedral_hist.counts.size(); ++b)
    s.min_dihedral_hist.counts[b] += o.min_dihedral_hist.counts[b];
  for (std::size_t b = 0; b < s.radius_ratio_hist.counts.size(); ++b)
    s.radius_ratio_hist.counts[b] += o.radius_ratio_hist.counts[b];
}

}  // namespace

QualitySummary summarize_quality(const PointSet& points, const std::vector<std::uint32_t>& tets,
                                 const TetQualityVisitor& each) {
  const std::size_t n = tets.size() / 4;
  constexpr std::size_t kBlock = 1 << 16;  // fixed: the sums' order is the same on any machine
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<Partial> part(blocks);
  parallel_for(blocks, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t k = b; k < e; ++k) {
      Partial p = empty_partial();
      for (std::size_t t = k * kBlock; t < std::min(n, (k + 1) * kBlock); ++t) {
        const std::uint32_t* v = &tets[4 * t];
        const TetQuality q = tet_quality(points.p(v[0]), points.p(v[1]), points.p(v[2]), points.p(v[3]));
        add_tet(p, q);
        if (each) each(t, q);
      }
      part[k] = std::move(p);
    }
  }, 1);
  Partial all = empty_partial();
  for (const Partial& p : part) merge(all, p);
  QualitySummary s = std::move(all.s);
  s.tets = n;
  if (n == 0) {  // the empty mesh's figures, as ever: zeros
    s.min_dihedral = s.max_dihedral = s.min_radius_ratio = s.min_volume_length = 0;
    return s;
  }
  s.mean_radius_ratio = all.sum_rr / double(n);
  s.mean_volume_length = all.sum_vl / double(n);
  return s;
}

QualitySummary summarize_quality(const TetMesh& mesh, std::vector<TetQuality>* per_tet) {
  if (per_tet) per_tet->assign(mesh.num_tets(), TetQuality{});
  TetQualityVisitor keep;
  if (per_tet) keep = [per_tet](std::size_t t, const TetQuality& q) { (*per_tet)[t] = q; };
  return summarize_quality(mesh.points, mesh.tets, keep);
}

}  // namespace kdmesh
