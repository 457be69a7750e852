// SPDX-License-Identifier: AGPL-3.0-or-later
#include "core/point_set.h"

#include <algorithm>

#include <cfloat>
#include <cmath>

namespace kdmesh {

std::size_t first_non_finite(const PointSet& points) {
  for (std::size_t i = 0; i < points.xyz.size(); ++i)
    if (!std::isfinite(points.xyz[i])) return i / 3;
  return points.size();
}

int unit_scale_exponent(const PointSet& points) {
  double hi = 0, lo = INFINITY;
  for (const double v : points.xyz) {
    const double a = std::fabs(v);
    if (a > hi) hi = a;
    if (a > 0 && a < lo) lo = a;
  }
  if (hi == 0 || !std::isfinite(hi)) return 0;
  int e;
  std::frexp(hi, &e);  // hi = m * 2^e, 0.5 <= m < 1
  const int k = -e;
  if (std::ldexp(lo, k) < DBL_MIN) return 0;  // would lose bits of the smallest coordinate
  return k;
}

int magnitude_scale_exponent(const PointSet& points) {
  double hi = 0;
  for (const double v : points.xyz) hi = std::max(hi, std::fabs(v));
  if (hi == 0 || !std::isfinite(hi)) return 0;
  int e;
  std::frexp(hi, &e);
  return -e;
}

PointSet scaled_copy(const PointSet& points, int exponent) {
  PointSet out;
  out.xyz.resize(points.xyz.size());
  for (std::size_t i = 0; i < points.xyz.size(); ++i) out.xyz[i] = std::ldexp(points.xyz[i], exponent);
  return out;
}

}  // namespace kdmesh
