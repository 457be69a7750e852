// kdmesh — the paper's seven point distributions (Fig. 6).
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Every model lives in (roughly) the unit cube. Points are disturbed slightly off the model
// ("Points are all disturbed a little away from their geometry model", Sect. 3.1) by an
// offset t drawn uniformly in [-delta, delta), delta = 1e-4, along the model's unit normal
// (surfaces) or independently along the two directions perpendicular to a segment (axes).
// All randomness comes from one kdmesh::Rng(seed), consumed in the order written below;
// u ~ U[0,1) is Rng::uniform(), U[a,b) is Rng::uniform(a, b), t ~ U[-delta, delta).
//
//  cube:       (x, y, z) = (u, u, u): uniform in [0,1)^3, not disturbed.
//  planes:     three mutually orthogonal planes x = 0.5, y = 0.5, z = 0.5 clipped to the
//              unit cube. Each point picks its plane j = Rng::below(3) at random, then two
//              in-plane coordinates a, b ~ U[0,1) (for the two other axes in x, y, z
//              order), then its coordinate on axis j is 0.5 + t.
//  paraboloid: z = 4((x-.5)^2 + (y-.5)^2) over the disk of radius 0.5 centred at (.5,.5),
//              (x, y) uniform in the disk; the point is moved by t along the unit normal
//              (-8(x-.5), -8(y-.5), 1) / sqrt(1 + 64 r^2). Surface heights are in [0, 1].
//  spiral:     a rolled sheet: the Archimedean spiral r(theta) = 0.05 + c*theta,
//              c = 0.45/(6 pi), theta in [0, 6 pi] (three turns, r from 0.05 to 0.5, turns
//              0.15 apart) around the axis x = y = 0.5, extruded along z in [0,1). Uniform
//              by area: theta has density proportional to the arc-length element
//              sqrt(r^2 + c^2) (exactly, by rejection from the density r + c), z ~ U[0,1);
//              the point is moved by t along the sheet's unit normal
//              (r cos + c sin, r sin - c cos) / sqrt(r^2 + c^2).
//  disk:       uniform in the disk of radius 0.5 centred at (.5,.5,.5) in the plane
//              z = 0.5; z = 0.5 + t.
//  cylinder:   lateral surface of the cylinder of radius 0.5, axis x = y = 0.5, z in [0,1):
//              uniform direction phi, z ~ U[0,1), radius 0.5 + t.
//  axes:       three segments from the origin along +x, +y, +z, length 1 each. Each point
//              picks its axis j = Rng::below(3), its position s ~ U[0,1) along it, then the
//              two other coordinates are t1, t2 (each U[-delta, delta), in x, y, z order).
//
// The two practical models (not in all_distributions(); see practical_distributions()) stand
// in for the paper's "constrained block" of Sect. 3.3 (Fig. 8, Tables 16-17) until the
// surface pipeline can mesh it. They are not disturbed: they are volume nodes, not surfaces.
//
//  constrained-cube: nodes in the unit cube whose spacing is fine near three constrained
//      edges and grows away from them. The paper's block has "three of its six edges
//      constrained in a wireframe structure"; we take the three edges that meet at the
//      corner O = (0,0,0), pairwise orthogonal: E0 = {y=0,z=0} (along x), E1 = {x=0,z=0}
//      (along y), E2 = {x=0,y=0} (along z). Inside the cube the distance to E0 is
//      d0 = sqrt(y^2+z^2) (to E1: sqrt(x^2+z^2), to E2: sqrt(x^2+y^2)), d = min(d0,d1,d2).
//      Target spacing h(d) = min(H, h0 + g d) with h0 = 1, H = 10, g = 30 in units of h0
//      (only the shape matters: the point count fixes the scale). So h grows linearly from
//      h0 on the edges to H = 10 h0 at d* = (H - h0)/g = 0.3 and is constant beyond it.
//      The total mass of h^-3 over the cube is M ~ 0.00279 h0^-3, so for n = 4.4M the
//      absolute spacing (one node per h^3) is h0 ~ 0.00086, H ~ 0.0086, g ~ 0.026: a gently
//      graded mesh with ~70% of its nodes within 0.3 of the edges.
//      Points are i.i.d. with density f(x) proportional to h(d(x))^-3 on [0,1)^3, so exactly
//      n points are produced. Writing c = H^-3 and e_i = h(d_i)^-3 - c >= 0 (zero for
//      d_i >= d*), f = c + max_i e_i <= c + e_0 + e_1 + e_2 =: q. Each point is drawn by
//      rejection from q, which is a mixture of exactly samplable parts:
//        1. u ~ U[0,1); if u (c + 3 Me) < c (Me = mass of one e_i, below): propose
//           (x, y, z) = (u, u, u) uniform in the cube;
//        2. otherwise the tube of edge i = Rng::below(3): the radius rho in [0, d*] with
//           density proportional to rho h(rho)^-3 by its exact inverse CDF,
//           s = h0 / (1 - sqrt(u) (1 - h0/H)), rho = (s - h0)/g, accepted with probability
//           1 - (s/H)^3 (rejection down to rho e_i(rho)), else redrawn from the inverse CDF;
//           then a direction (cx, cy) as in unit_direction() with |cx|, |cy| (uniform angle
//           in [0, pi/2]); the cross-section is (a, b) = rho (|cx|, |cy|) and the coordinate
//           along the edge t ~ U[0,1): E0 -> (t, a, b), E1 -> (a, t, b), E2 -> (a, b, t);
//      then the proposal is accepted when u (c + e_0 + e_1 + e_2) < c + max(e_0, e_1, e_2)
//      (always where at most one tube reaches; overall ~96% of proposals are accepted), else redrawn
//      from step 1. Me = (pi/2) [(1 - h0/H)^2 / (2 h0 g^2) - d*^2 / (2 H^3)] (the integral of
//      rho h^-3 is (1 - h0/s)^2 / (2 h0 g^2)). Near the edges the density is up to
//      (H/h0)^3 = 1000 times the far density, e.g. at least (10/2.5)^3 = 64 times it
//      everywhere within 0.05 of an edge (h <= 1 + 30 * 0.05 = 2.5 there).
//  refined-constrained-cube: emulates the paper's 5.5M case, "built by adding some nodes on
//      element edges of the tet-mesh of the constrained cube". We have no tet mesh to take
//      edges from, so: m = n / 5 (integer division) added nodes, and the n - m base points
//      are exactly constrained-cube(n - m, seed) (so -n 5500000 has the 4.4M constrained
//      cube as its first 4.4M points). The base points are sorted on their 63-bit Morton
//      key (21 bits per axis, floor(x 2^21); ties by index), and for k = 0..m-1 the
//      midpoint 0.5 (p + q) of the sorted points p = s[4k], q = s[4k+1] is appended, in
//      that order. Every 4th Morton-consecutive pair is usually two nearby nodes, i.e. a
//      short segment like a mesh edge, and the midpoints follow the node density as the
//      paper's edge nodes would. It is only an emulation: the pairs are curve neighbours,
//      not Delaunay edges (at a jump of the Morton curve a pair can be far apart), and the
//      midpoints are not those of the paper. The pairs are disjoint and midpoints lie
//      strictly between two distinct points, so there are no duplicates (barring two
//      identical 53-bit draws). No Rng is used beyond the base points.
//
// Points uniform in a disk, and uniform directions, come from rejection sampling of
// (v, w) ~ U[-1,1)^2 with v^2 + w^2 <= 1 (and != 0 for directions). Bit-identical results
// on every platform: only IEEE-exact operations (+ - * / sqrt) are used (the build disables
// FMA contraction); the spiral's cos/sin come from our own polynomial, not libm.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>

#include "core/error.h"
#include "core/rng.h"
#include "tools/bench/lib/distributions.h"

namespace kdmesh {

namespace {

constexpr double kDelta = 1e-4;
constexpr double kPi = 3.141592653589793;

struct DistName {
  Distribution d;
  const char* name;
};

constexpr DistName kDists[] = {
    {Distribution::cube, "cube"},         {Distribution::planes, "planes"},
    {Distribution::paraboloid, "paraboloid"}, {Distribution::spiral, "spiral"},
    {Distribution::disk, "disk"},         {Distribution::cylinder, "cylinder"},
    {Distribution::axes, "axes"},
};

constexpr DistName kPractical[] = {
    {Distribution::constrained_cube, "constrained-cube"},
    {Distribution::refined_constrained_cube, "refined-constrained-cube"},
};

double disturbance(Rng& rng) { return rng.uniform(-kDelta, kDelta); }

/// (v, w) uniform in the closed unit disk (rejection from the square [-1,1)^2).
void unit_disk(Rng& rng, double& v, double& w) {
  for (;;) {
    v = rng.uniform(-1.0, 1.0);
    w = rng.uniform(-1.0, 1.0);
    if (v * v + w * w <= 1.0) return;
  }
}

/// Uniform unit vector (cx, cy) of the plane.
void unit_direction(Rng& rng, double& cx, double& cy) {
  for (;;) {
    const double v = rng.uniform(-1.0, 1.0);
    const double w = rng.uniform(-1.0, 1.0);
    const double s = v * v + w * w;
    if (s > 0.0 && s <= 1.0) {
      const double len = std::sqrt(s);
      cx = v / len;
      cy = w / len;
      return;
    }
  }
}

/// sin and cos of theta in [0, 8 pi], using only + - * / so that the result is the same on
/// every platform. Cody-Waite reduction by pi/2 (fdlibm's two-part constant: k * kPio2Hi
/// is exact for k < 2^20), then Taylor polynomials on |r| <= pi/4 (truncation < 1e-19).
void det_sincos(double theta, double& s, double& c) {
  constexpr double kPio2Hi = 1.57079632673412561417e+00;
  constexpr double kPio2Lo = 6.07710050650619224932e-11;
  const double kf = std::floor(theta / (kPi / 2) + 0.5);
  const double r = (theta - kf * kPio2Hi) - kf * kPio2Lo;
  const double r2 = r * r;
  // sin r = r (1 - r2/(2*3) (1 - r2/(4*5) (1 - ...))), nested up to r^17.
  double ps = 1.0;
  for (int m = 16; m >= 2; m -= 2) ps = 1.0 - r2 / double(m * (m + 1)) * ps;
  const double sr = r * ps;
  // cos r = 1 - r2/(1*2) (1 - r2/(3*4) (1 - ...)), nested up to r^18.
  double pc = 1.0;
  for (int m = 17; m >= 1; m -= 2) pc = 1.0 - r2 / double(m * (m + 1)) * pc;
  const double cr = pc;
  switch (static_cast<long long>(kf) & 3) {
    case 0: s = sr; c = cr; break;
    case 1: s = cr; c = -sr; break;
    case 2: s = -sr; c = -cr; break;
    default: s = -cr; c = sr; break;
  }
}

void gen_cube(Rng& rng, PointSet& ps) {
  const double x = rng.uniform();
  const double y = rng.uniform();
  const double z = rng.uniform();
  ps.push_back(x, y, z);
}

void gen_planes(Rng& rng, PointSet& ps) {
  const int j = int(rng.below(3));
  const double a = rng.uniform();
  const double b = rng.uniform();
  const double t = 0.5 + disturbance(rng);
  if (j == 0) ps.push_back(t, a, b);
  else if (j == 1) ps.push_back(a, t, b);
  else ps.push_back(a, b, t);
}

void gen_paraboloid(Rng& rng, PointSet& ps) {
  double v, w;
  unit_disk(rng, v, w);
  const double dx = 0.5 * v, dy = 0.5 * w;
  const double r2 = dx * dx + dy * dy;
  const double z = 4.0 * r2;
  const double len = std::sqrt(1.0 + 64.0 * r2);
  const double t = disturbance(rng);
  ps.push_back(0.5 + dx + t * (-8.0 * dx / len), 0.5 + dy + t * (-8.0 * dy / len),
               z + t * (1.0 / len));
}

void gen_spiral(Rng& rng, PointSet& ps) {
  constexpr double r0 = 0.05, r1 = 0.5;
  constexpr double c = 0.45 / (6.0 * kPi);
  // Density of r (equivalently theta) proportional to sqrt(r^2 + c^2): propose w = r + c
  // with density proportional to w (w^2 uniform), accept with sqrt(r^2 + c^2) / (r + c).
  constexpr double w0 = r0 + c, w1 = r1 + c;
  double r;
  for (;;) {
    const double w = std::sqrt(w0 * w0 + rng.uniform() * (w1 * w1 - w0 * w0));
    r = w - c;
    if (r < r0) r = r0;  // rounding guard
    if (r > r1) r = r1;
    if (rng.uniform() * (r + c) < std::sqrt(r * r + c * c)) break;
  }
  const double theta = (r - r0) / c;
  const double z = rng.uniform();
  const double t = disturbance(rng);
  double sn, cs;
  det_sincos(theta, sn, cs);
  const double len = std::sqrt(r * r + c * c);
  const double nx = (r * cs + c * sn) / len;
  const double ny = (r * sn - c * cs) / len;
  ps.push_back(0.5 + r * cs + t * nx, 0.5 + r * sn + t * ny, z);
}

void gen_disk(Rng& rng, PointSet& ps) {
  double v, w;
  unit_disk(rng, v, w);
  const double t = disturbance(rng);
  ps.push_back(0.5 + 0.5 * v, 0.5 + 0.5 * w, 0.5 + t);
}

void gen_cylinder(Rng& rng, PointSet& ps) {
  double cx, cy;
  unit_direction(rng, cx, cy);
  const double z = rng.uniform();
  const double rad = 0.5 + disturbance(rng);
  ps.push_back(0.5 + rad * cx, 0.5 + rad * cy, z);
}

void gen_axes(Rng& rng, PointSet& ps) {
  const int j = int(rng.below(3));
  const double s = rng.uniform();
  const double t1 = disturbance(rng);
  const double t2 = disturbance(rng);
  if (j == 0) ps.push_back(s, t1, t2);
  else if (j == 1) ps.push_back(t1, s, t2);
  else ps.push_back(t1, t2, s);
}

// constrained-cube: spacing field h(d) = min(kCcH, kCcH0 + kCcG d), see the header comment.
constexpr double kCcH0 = 1.0;
constexpr double kCcH = 10.0;
constexpr double kCcG = 30.0;
constexpr double kCcDStar = (kCcH - kCcH0) / kCcG;  // 0.3
constexpr double kCcC = 1.0 / (kCcH * kCcH * kCcH);  // H^-3, the far density
// Mass of one tube term e_i over the cube.
constexpr double kCcTube = (kPi / 2) * ((1.0 - kCcH0 / kCcH) * (1.0 - kCcH0 / kCcH) /
                                            (2.0 * kCcH0 * kCcG * kCcG) -
                                        kCcDStar * kCcDStar / 2.0 * kCcC);

/// e = h(d)^-3 - H^-3 for the squared distance d2 = d^2 to one edge (0 for d >= d*).
double cc_excess(double d2) {
  const double d = std::sqrt(d2);
  if (d >= kCcDStar) return 0.0;
  const double h = kCcH0 + kCcG * d;
  if (h >= kCcH) return 0.0;
  return 1.0 / (h * h * h) - kCcC;
}

void gen_constrained_cube(Rng& rng, PointSet& ps) {
  for (;;) {
    double x, y, z;
    const double u = rng.uniform();
    if (u * (kCcC + 3.0 * kCcTube) < kCcC) {
      x = rng.uniform();
      y = rng.uniform();
      z = rng.uniform();
    } else {
      const int j = int(rng.below(3));
      double s;
      for (;;) {
        s = kCcH0 / (1.0 - std::sqrt(rng.uniform()) * (1.0 - kCcH0 / kCcH));
        if (s > kCcH) s = kCcH;  // rounding guard
        if (rng.uniform() * (kCcH * kCcH * kCcH) < kCcH * kCcH * kCcH - s * s * s) break;
      }
      const double rho = (s - kCcH0) / kCcG;
      double cx, cy;
      unit_direction(rng, cx, cy);
      const double a = rho * std::abs(cx), b = rho * std::abs(cy);
      const double t = rng.uniform();
      if (j == 0) {
        x = t; y = a; z = b;
      } else if (j == 1) {
        x = a; y = t; z = b;
      } else {
        x = a; y = b; z = t;
      }
    }
    const double e0 = cc_excess(y * y + z * z);
    const double e1 = cc_excess(x * x + z * z);
    const double e2 = cc_excess(x * x + y * y);
    const double target = kCcC + std::max(e0, std::max(e1, e2));
    const double proposal = kCcC + e0 + e1 + e2;
    if (rng.uniform() * proposal < target) {
      ps.push_back(x, y, z);
      return;
    }
  }
}

/// 21 bits of v spread to every third bit.
std::uint64_t spread3(std::uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

std::uint64_t morton_cell(double v) {
  const double q = std::floor(v * 2097152.0);  // 2^21
  if (!(q > 0.0)) return 0;
  if (q >= 2097151.0) return 2097151;
  return std::uint64_t(q);
}

PointSet gen_refined_constrained_cube(std::size_t n, std::uint64_t seed) {
  const std::size_t m = n / 5;
  const std::size_t nb = n - m;
  PointSet ps;
  ps.xyz.reserve(3 * n);
  Rng rng(seed);
  for (std::size_t i = 0; i < nb; ++i) gen_constrained_cube(rng, ps);
  if (m == 0) return ps;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> key(nb);
  for (std::size_t i = 0; i < nb; ++i) {
    const double* p = ps.p(std::uint32_t(i));
    key[i] = {spread3(morton_cell(p[0])) | spread3(morton_cell(p[1])) << 1 |
                  spread3(morton_cell(p[2])) << 2,
              std::uint32_t(i)};
  }
  std::sort(key.begin(), key.end());  // (key, index): a total order, so deterministic
  for (std::size_t k = 0; k < m; ++k) {
    const double* p = ps.xyz.data() + 3 * std::size_t(key[4 * k].second);
    const double* q = ps.xyz.data() + 3 * std::size_t(key[4 * k + 1].second);
    const double mx = 0.5 * (p[0] + q[0]), my = 0.5 * (p[1] + q[1]), mz = 0.5 * (p[2] + q[2]);
    ps.push_back(mx, my, mz);  // reserved: p and q stay valid
  }
  return ps;
}

}  // namespace

Distribution parse_distribution(std::string_view name) {
  for (const DistName& d : kDists) {
    if (name == d.name) return d.d;
  }
  for (const DistName& d : kPractical) {
    if (name == d.name) return d.d;
  }
  std::string valid;
  for (const DistName& d : kDists) valid += (valid.empty() ? "" : ", ") + std::string(d.name);
  for (const DistName& d : kPractical) valid += ", " + std::string(d.name);
  throw UsageError("unknown distribution '" + std::string(name) + "' (valid: " + valid + ")");
}

std::string_view distribution_name(Distribution d) {
  for (const DistName& e : kDists) {
    if (d == e.d) return e.name;
  }
  for (const DistName& e : kPractical) {
    if (d == e.d) return e.name;
  }
  throw UsageError("unknown distribution " + std::to_string(int(d)));
}

std::vector<Distribution> all_distributions() {
  std::vector<Distribution> v;
  for (const DistName& d : kDists) v.push_back(d.d);
  return v;
}

std::vector<Distribution> practical_distributions() {
  std::vector<Distribution> v;
  for (const DistName& d : kPractical) v.push_back(d.d);
  return v;
}

PointSet generate_points(Distribution d, std::size_t n, std::uint64_t seed) {
  if (d == Distribution::refined_constrained_cube) return gen_refined_constrained_cube(n, seed);
  void (*gen)(Rng&, PointSet&) = nullptr;
  switch (d) {
    case Distribution::cube: gen = gen_cube; break;
    case Distribution::planes: gen = gen_planes; break;
    case Distribution::paraboloid: gen = gen_paraboloid; break;
    case Distribution::spiral: gen = gen_spiral; break;
    case Distribution::disk: gen = gen_disk; break;
    case Distribution::cylinder: gen = gen_cylinder; break;
    case Distribution::axes: gen = gen_axes; break;
    case Distribution::constrained_cube: gen = gen_constrained_cube; break;
    default: throw UsageError("unknown distribution " + std::to_string(int(d)));
  }
  PointSet ps;
  ps.xyz.reserve(3 * n);
  Rng rng(seed);
  for (std::size_t i = 0; i < n; ++i) gen(rng, ps);
  return ps;
}

}  // namespace kdmesh
