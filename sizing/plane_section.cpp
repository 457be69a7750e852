// kdmesh — cross-section of a closed surface's solid with a plane, and a point-in-section test.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "sizing/plane_section.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace kdmesh {
namespace {

double dot3(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

void cross3(const double* a, const double* b, double* out) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

void normalize3(double* a) {
  const double n = std::sqrt(dot3(a, a));
  a[0] /= n;
  a[1] /= n;
  a[2] /= n;
}

}  // namespace

namespace {

/// One cut; zero_above says on which side points with s == 0 count.
PlaneSection cut(const SurfaceMesh& surface, const double origin[3], const double normal[3],
                 bool zero_above) {
  PlaneSection sec;
  for (int k = 0; k < 3; ++k) {
    sec.origin[k] = origin[k];
    sec.normal[k] = normal[k];
  }
  normalize3(sec.normal);
  // u: normal × (the axis along which the normal is smallest), so u is far from parallel.
  const double* n = sec.normal;
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (std::fabs(n[k]) < std::fabs(n[axis])) axis = k;
  double e[3] = {0, 0, 0};
  e[axis] = 1;
  cross3(n, e, sec.u);
  normalize3(sec.u);
  cross3(n, sec.u, sec.v);
  normalize3(sec.v);

  const std::size_t np = surface.points.size();
  std::vector<double> s(np);
  for (std::size_t i = 0; i < np; ++i) {
    const double* p = surface.points.p(std::uint32_t(i));
    const double d[3] = {p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]};
    s[i] = dot3(d, n);
  }
  std::unordered_map<std::uint64_t, std::uint32_t> edge_point;
  auto crossing = [&](std::uint32_t a, std::uint32_t b) -> std::uint32_t {
    const std::uint32_t lo = std::min(a, b), hi = std::max(a, b);
    const std::uint64_t key = (std::uint64_t(lo) << 32) | hi;
    auto [it, fresh] = edge_point.try_emplace(key, std::uint32_t(sec.xyz.size() / 3));
    if (!fresh) return it->second;
    const double* pl = surface.points.p(lo);
    const double* ph = surface.points.p(hi);
    double q[3];
    if (s[lo] == 0) {
      for (int k = 0; k < 3; ++k) q[k] = pl[k];
    } else if (s[hi] == 0) {
      for (int k = 0; k < 3; ++k) q[k] = ph[k];
    } else {
      const double t = s[lo] / (s[lo] - s[hi]);  // signs differ: denominator is not zero
      for (int k = 0; k < 3; ++k) q[k] = pl[k] + t * (ph[k] - pl[k]);
    }
    const double d[3] = {q[0] - origin[0], q[1] - origin[1], q[2] - origin[2]};
    sec.xyz.insert(sec.xyz.end(), q, q + 3);
    sec.uv.push_back(dot3(d, sec.u));
    sec.uv.push_back(dot3(d, sec.v));
    return it->second;
  };

  for (std::size_t f = 0; f < surface.num_tris(); ++f) {
    const std::uint32_t* t = surface.tri(f);
    if (t[0] >= np || t[1] >= np || t[2] >= np) continue;
    auto up = [&](std::uint32_t i) { return zero_above ? s[i] >= 0 : s[i] > 0; };
    const bool above[3] = {up(t[0]), up(t[1]), up(t[2])};
    if (above[0] == above[1] && above[1] == above[2]) continue;
    std::uint32_t ends[2];
    int m = 0;
    for (int k = 0; k < 3; ++k) {
      const int k1 = (k + 1) % 3;
      if (above[k] != above[k1]) ends[m++] = crossing(t[k], t[k1]);
    }
    // Exactly two edges of a triangle change side. Zero-length segments (a triangle touching
    // the plane at one point) are dropped: they change neither parity nor distance.
    const double* a = sec.xyz.data() + 3 * std::size_t(ends[0]);
    const double* b = sec.xyz.data() + 3 * std::size_t(ends[1]);
    if (a[0] == b[0] && a[1] == b[1] && a[2] == b[2]) continue;
    sec.segs.push_back(ends[0]);
    sec.segs.push_back(ends[1]);
  }
  return sec;
}

}  // namespace

PlaneSection cut_with_plane(const SurfaceMesh& surface, const double origin[3],
                            const double normal[3]) {
  PlaneSection sec = cut(surface, origin, normal, true);
  if (sec.empty()) sec = cut(surface, origin, normal, false);  // a plane touching the solid
  return sec;
}

SectionLocator::SectionLocator(const PlaneSection& section) {
  const std::size_t ns = section.num_segments();
  if (ns == 0) return;
  seg_uv_.resize(4 * ns);
  bbox_[0] = bbox_[2] = INFINITY;
  bbox_[1] = bbox_[3] = -INFINITY;
  for (std::size_t i = 0; i < ns; ++i) {
    for (int e = 0; e < 2; ++e) {
      const double* q = section.uv.data() + 2 * std::size_t(section.segs[2 * i + e]);
      seg_uv_[4 * i + 2 * e] = q[0];
      seg_uv_[4 * i + 2 * e + 1] = q[1];
      bbox_[0] = std::min(bbox_[0], q[0]);
      bbox_[1] = std::max(bbox_[1], q[0]);
      bbox_[2] = std::min(bbox_[2], q[1]);
      bbox_[3] = std::max(bbox_[3], q[1]);
    }
  }
  num_slabs_ = std::uint32_t(std::clamp<std::size_t>(ns, 1, 1u << 16));
  const double height = bbox_[3] - bbox_[2];
  inv_slab_ = height > 0 ? double(num_slabs_) / height : 0;
  // Counting sort of segments into the slabs their v-range covers. slab_of is monotone in v,
  // so a query's slab is within the range of every segment whose v-range contains the query.
  slab_start_.assign(std::size_t(num_slabs_) + 1, 0);
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<std::uint32_t> fill;
    if (pass == 1) {
      for (std::uint32_t k = 0; k < num_slabs_; ++k) slab_start_[k + 1] += slab_start_[k];
      slab_segs_.resize(slab_start_[num_slabs_]);
      fill.assign(slab_start_.begin(), slab_start_.end() - 1);
    }
    for (std::size_t i = 0; i < ns; ++i) {
      const double va = seg_uv_[4 * i + 1], vb = seg_uv_[4 * i + 3];
      const std::uint32_t s0 = slab_of(std::min(va, vb)), s1 = slab_of(std::max(va, vb));
      for (std::uint32_t k = s0; k <= s1; ++k) {
        if (pass == 0)
          ++slab_start_[k + 1];
        else
          slab_segs_[fill[k]++] = std::uint32_t(i);
      }
    }
  }
}

std::uint32_t SectionLocator::slab_of(double pv) const {
  const double f = (pv - bbox_[2]) * inv_slab_;
  if (!(f > 0)) return 0;
  if (f >= double(num_slabs_)) return num_slabs_ - 1;
  return std::uint32_t(f);
}

bool SectionLocator::contains(double pu, double pv) const {
  if (!(pu >= bbox_[0] && pu <= bbox_[1] && pv >= bbox_[2] && pv <= bbox_[3])) return false;
  const std::uint32_t slab = slab_of(pv);
  bool inside = false;
  for (std::uint32_t k = slab_start_[slab]; k < slab_start_[slab + 1]; ++k) {
    const double* q = seg_uv_.data() + 4 * std::size_t(slab_segs_[k]);
    const double ua = q[0], va = q[1], ub = q[2], vb = q[3];
    if ((va > pv) == (vb > pv)) continue;  // half-open: [min v, max v)
    // The ray's crossing with the segment, computed from the lower end (a fixed order, so
    // the result does not depend on how the segment is stored).
    const bool a_low = va < vb;
    const double ul = a_low ? ua : ub, vl = a_low ? va : vb;
    const double uh = a_low ? ub : ua, vh = a_low ? vb : va;
    const double ux = ul + (pv - vl) * ((uh - ul) / (vh - vl));
    if (ux > pu) inside = !inside;
  }
  return inside;
}

}  // namespace kdmesh
