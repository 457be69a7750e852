// kdmesh — small 3-vector helpers of the surface analyses in sizing/.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <array>
#include <cmath>

namespace kdmesh::vec3 {

using Vec3 = std::array<double, 3>;

inline Vec3 sub(const double* a, const double* b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }

/// Angle in radians between a and b, in [0, pi]; atan2 form, accurate near 0 and pi. A zero
/// vector (degenerate facet or edge) gives 0 when both are zero, pi/2 otherwise (atan2(0,0)=0).
inline double angle_between(const Vec3& a, const Vec3& b) { return std::atan2(norm(cross(a, b)), dot(a, b)); }

}  // namespace kdmesh::vec3
