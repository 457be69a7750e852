// kdmesh — tests of the tetrahedron shape measures (mesher/tet_quality.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "mesher/tet_quality.h"

namespace kdmesh {
namespace {

const double kPi = std::acos(-1.0);
double deg(double rad) { return rad * 180 / kPi; }

// Regular tet of edge 2*sqrt(2) (alternate corners of the cube [-1,1]^3), ordered positively:
// det[b-a, d-a, c-a] with b-a=(0,-2,-2), c-a=(-2,0,-2), d-a=(-2,-2,0) is +16, so (a,b,d,c).
TEST(TetQuality, RegularTet) {
  const double a[3] = {1, 1, 1}, b[3] = {1, -1, -1}, c[3] = {-1, 1, -1}, d[3] = {-1, -1, 1};
  const TetQuality q = tet_quality(a, b, d, c);
  EXPECT_NEAR(q.volume, 16.0 / 6, 1e-12);  // = l^3 / (6 sqrt 2) with l = 2 sqrt 2
  // Every dihedral of the regular tet is acos(1/3) = 70.5288 degrees.
  EXPECT_NEAR(q.min_dihedral, deg(std::acos(1.0 / 3)), 1e-9);
  EXPECT_NEAR(q.max_dihedral, deg(std::acos(1.0 / 3)), 1e-9);
  EXPECT_NEAR(q.radius_ratio, 1.0, 1e-12);
  EXPECT_NEAR(q.radius_edge, std::sqrt(6.0) / 4, 1e-12);
  EXPECT_NEAR(q.volume_length, 1.0, 1e-12);
}

// The corner tet (0, e1, e2, e3):
//  - dihedrals along the axes are 90 degrees (between coordinate planes); along the three
//    edges e_i-e_j, between the coordinate plane (normal -e_k) and the face x+y+z=1 (normal
//    (1,1,1)/sqrt 3): pi - acos(-1/sqrt 3) = acos(1/sqrt 3) = 54.7356 degrees;
//  - V = 1/6; area = 3/2 + sqrt(3)/2; r_in = 3V/area = 1/(3+sqrt 3); circumcentre (1/2,1/2,1/2)
//    so R = sqrt(3)/2; gamma = 3 r_in / R = 2/(sqrt(3)+1) = sqrt(3) - 1;
//  - shortest edge 1: radius-edge = sqrt(3)/2;
//  - edges: three of length 1, three of sqrt 2: l_rms^2 = (3 + 6)/6 = 3/2;
//    volume-length = 6 sqrt(2) (1/6) / (3/2)^(3/2) = sqrt(2) / (3/2)^(3/2).
TEST(TetQuality, CornerTet) {
  const double o[3] = {0, 0, 0}, x[3] = {1, 0, 0}, y[3] = {0, 1, 0}, z[3] = {0, 0, 1};
  const TetQuality q = tet_quality(o, x, y, z);
  EXPECT_NEAR(q.volume, 1.0 / 6, 1e-15);
  EXPECT_NEAR(q.min_dihedral, deg(std::acos(1 / std::sqrt(3.0))), 1e-9);
  EXPECT_NEAR(q.max_dihedral, 90.0, 1e-9);
  EXPECT_NEAR(q.radius_ratio, std::sqrt(3.0) - 1, 1e-12);
  EXPECT_NEAR(q.radius_edge, std::sqrt(3.0) / 2, 1e-12);
  EXPECT_NEAR(q.volume_length, std::sqrt(2.0) / std::pow(1.5, 1.5), 1e-12);
}

// Measures do not depend on position, scale or which vertex comes first (even permutation).
TEST(TetQuality, InvariantUnderSimilarityAndEvenPermutation) {
  const double o[3] = {0, 0, 0}, x[3] = {1, 0, 0}, y[3] = {0, 1, 0}, z[3] = {0, 0, 1};
  const TetQuality q0 = tet_quality(o, x, y, z);
  auto m = [](const double* p) { return std::array<double, 3>{3 * p[0] + 5, 3 * p[1] - 7, 3 * p[2] + 1}; };
  const auto O = m(o), X = m(x), Y = m(y), Z = m(z);
  const TetQuality q1 = tet_quality(X.data(), O.data(), Z.data(), Y.data());  // (x o z y): even
  EXPECT_NEAR(q1.volume, 27.0 / 6, 1e-12);
  EXPECT_NEAR(q1.min_dihedral, q0.min_dihedral, 1e-9);
  EXPECT_NEAR(q1.max_dihedral, q0.max_dihedral, 1e-9);
  EXPECT_NEAR(q1.radius_ratio, q0.radius_ratio, 1e-12);
  EXPECT_NEAR(q1.radius_edge, q0.radius_edge, 1e-12);
  EXPECT_NEAR(q1.volume_length, q0.volume_length, 1e-12);
}

// A sliver: the unit square's corners, two diagonally opposite ones lifted by eps. Its
// dihedrals tend to 0 and 180 degrees and every ratio to 0 as eps -> 0. (0,0,0),(1,1,0),
// (1,0,e),(0,1,e): det[(1,1,0),(1,0,e),(0,1,e)] = 1(0-e) - 1(e-0) + 0 = -2e < 0, so swap the
// last two: volume 2e/6.
TEST(TetQuality, FlatSliver) {
  const double e = 1e-6;
  const double a[3] = {0, 0, 0}, b[3] = {1, 1, 0}, c[3] = {1, 0, e}, d[3] = {0, 1, e};
  const TetQuality q = tet_quality(a, b, d, c);
  EXPECT_NEAR(q.volume, 2 * e / 6, 1e-18);
  EXPECT_LT(q.min_dihedral, 1e-3);
  EXPECT_GT(q.max_dihedral, 180 - 1e-3);
  EXPECT_GT(q.radius_ratio, 0);
  EXPECT_LT(q.radius_ratio, 1e-5);
  EXPECT_LT(q.volume_length, 1e-5);
}

// The extreme dihedrals are the smallest and largest of all six, each computed as pi less the
// angle between the two faces' outward normals (tet_quality takes the arc cosine of the
// extreme cosines only).
TEST(TetQuality, ExtremeDihedralsAreTheExtremesOfAllSix) {
  std::uint64_t x = 12345;
  auto uniform = [&] {  // a 64-bit LCG: enough for shapes
    x = x * 6364136223846793005ull + 1442695040888963407ull;
    return double(x >> 11) / double(1ull << 53);
  };
  for (int i = 0; i < 2000; ++i) {
    double p[4][3];
    for (auto& q : p)
      for (double& c : q) c = uniform();
    if (i % 4 == 0)
      for (int k = 0; k < 3; ++k) p[3][k] = p[0][k] + 1e-3 * (p[3][k] - p[0][k]);  // needles and slivers
    static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
    std::array<double, 3> n[4];
    for (int f = 0; f < 4; ++f) {
      const double* a = p[kFace[f][0]];
      const double* b = p[kFace[f][1]];
      const double* c = p[kFace[f][2]];
      const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      n[f] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
      const double len = std::hypot(n[f][0], n[f][1], n[f][2]);
      for (double& c2 : n[f]) c2 /= len;
    }
    double lo = 180, hi = 0;
    for (int k = 0; k < 4; ++k)
      for (int l = k + 1; l < 4; ++l) {
        const double c = n[k][0] * n[l][0] + n[k][1] * n[l][1] + n[k][2] * n[l][2];
        const double a = 180 - deg(std::acos(std::clamp(c, -1.0, 1.0)));
        lo = std::min(lo, a);
        hi = std::max(hi, a);
      }
    const TetQuality q = tet_quality(p[0], p[1], p[2], p[3]);
    ASSERT_NEAR(q.min_dihedral, lo, 1e-7) << "tet " << i;  // either orientation: both normals flip
    ASSERT_NEAR(q.max_dihedral, hi, 1e-7) << "tet " << i;
  }
}

TEST(TetQuality, InvertedAndDegenerate) {
  const double o[3] = {0, 0, 0}, x[3] = {1, 0, 0}, y[3] = {0, 1, 0}, z[3] = {0, 0, 1};
  const TetQuality inv = tet_quality(o, y, x, z);  // odd permutation of the corner tet
  EXPECT_NEAR(inv.volume, -1.0 / 6, 1e-15);
  EXPECT_LT(inv.radius_ratio, 0);
  EXPECT_LT(inv.volume_length, 0);
  const double w[3] = {1, 1, 0};  // coplanar with o, x, y
  const TetQuality flat = tet_quality(o, x, y, w);
  EXPECT_EQ(flat.volume, 0);
  EXPECT_EQ(flat.radius_ratio, 0);
  EXPECT_TRUE(std::isinf(flat.radius_edge));
}

// Summary of three tets: the regular tet (min dihedral 70.53 -> bin 14 of 5-degree bins,
// gamma 1 -> last bin), the corner tet (54.74 -> bin 10, gamma 0.732 -> bin 7) and the inverted
// corner tet (same dihedrals, mirror image: bin 10; gamma < 0 -> clamped to bin 0).
TEST(QualitySummary, CountsExtremesAndHistograms) {
  TetMesh m;
  const double pts[][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1},
                           {1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  for (auto& p : pts) m.points.push_back(p[0], p[1], p[2]);
  m.tets = {4, 5, 7, 6, 0, 1, 2, 3, 0, 2, 1, 3};
  std::vector<TetQuality> per;
  const QualitySummary s = summarize_quality(m, &per);
  ASSERT_EQ(per.size(), 3u);
  EXPECT_EQ(s.tets, 3u);
  EXPECT_EQ(s.inverted, 1u);
  EXPECT_NEAR(s.min_dihedral, deg(std::acos(1 / std::sqrt(3.0))), 1e-9);
  EXPECT_NEAR(s.max_dihedral, 90, 1e-9);
  EXPECT_NEAR(s.min_radius_ratio, -(std::sqrt(3.0) - 1), 1e-12);
  EXPECT_NEAR(s.mean_radius_ratio, 1.0 / 3, 1e-12);  // (1 + g - g) / 3
  ASSERT_EQ(s.min_dihedral_hist.counts.size(), 18u);
  ASSERT_EQ(s.radius_ratio_hist.counts.size(), 10u);
  EXPECT_EQ(s.min_dihedral_hist.counts[14], 1u);
  EXPECT_EQ(s.min_dihedral_hist.counts[10], 2u);
  EXPECT_EQ(s.radius_ratio_hist.counts[9], 1u);
  EXPECT_EQ(s.radius_ratio_hist.counts[7], 1u);
  EXPECT_EQ(s.radius_ratio_hist.counts[0], 1u);
}

}  // namespace
}  // namespace kdmesh
