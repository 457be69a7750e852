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
// Points uniform in a disk, and uniform directions, come from rejection sampling of
// (v, w) ~ U[-1,1)^2 with v^2 + w^2 <= 1 (and != 0 for directions). Bit-identical results
// on every platform: only IEEE-exact operations (+ - * / sqrt) are used (the build disables
// FMA contraction); the spiral's cos/sin come from our own polynomial, not libm.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/error.h"
#include "core/rng.h"
#include "tools/lib/distributions.h"

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

}  // namespace

Distribution parse_distribution(std::string_view name) {
  for (const DistName& d : kDists) {
    if (name == d.name) return d.d;
  }
  std::string valid;
  for (const DistName& d : kDists) valid += (valid.empty() ? "" : ", ") + std::string(d.name);
  throw UsageError("unknown distribution '" + std::string(name) + "' (valid: " + valid + ")");
}

std::string_view distribution_name(Distribution d) {
  for (const DistName& e : kDists) {
    if (d == e.d) return e.name;
  }
  throw UsageError("unknown distribution " + std::to_string(int(d)));
}

std::vector<Distribution> all_distributions() {
  std::vector<Distribution> v;
  for (const DistName& d : kDists) v.push_back(d.d);
  return v;
}

PointSet generate_points(Distribution d, std::size_t n, std::uint64_t seed) {
  void (*gen)(Rng&, PointSet&) = nullptr;
  switch (d) {
    case Distribution::cube: gen = gen_cube; break;
    case Distribution::planes: gen = gen_planes; break;
    case Distribution::paraboloid: gen = gen_paraboloid; break;
    case Distribution::spiral: gen = gen_spiral; break;
    case Distribution::disk: gen = gen_disk; break;
    case Distribution::cylinder: gen = gen_cylinder; break;
    case Distribution::axes: gen = gen_axes; break;
    default: throw UsageError("unknown distribution " + std::to_string(int(d)));
  }
  PointSet ps;
  ps.xyz.reserve(3 * n);
  Rng rng(seed);
  for (std::size_t i = 0; i < n; ++i) gen(rng, ps);
  return ps;
}

}  // namespace kdmesh
