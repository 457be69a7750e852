// kdmesh — the points of a boundary face at which its distance to the surface is measured:
// one set for the mesh check, the recovery's judgement and the quality pass, so that a face
// the mesher accepts is one the check accepts.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once

namespace kdmesh {

/// Barycentric weights of the 7 samples: the centroid, the 3 edge midpoints and the 3 points
/// half-way between the centroid and the corners. The centroid comes first.
inline constexpr double kFaceSamples[7][3] = {{1.0 / 3, 1.0 / 3, 1.0 / 3}, {0.5, 0.5, 0},       {0, 0.5, 0.5},
                                             {0.5, 0, 0.5},             {2.0 / 3, 1.0 / 6, 1.0 / 6},
                                             {1.0 / 6, 2.0 / 3, 1.0 / 6}, {1.0 / 6, 1.0 / 6, 2.0 / 3}};

/// Sample k (0..6) of the triangle (a, b, c), to out.
inline void face_sample(const double* a, const double* b, const double* c, int k, double* out) {
  const double* w = kFaceSamples[k];
  for (int q = 0; q < 3; ++q) out[q] = w[0] * a[q] + w[1] * b[q] + w[2] * c[q];
}

}  // namespace kdmesh
