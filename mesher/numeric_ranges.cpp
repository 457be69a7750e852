// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/numeric_ranges.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "core/error.h"

namespace kdmesh {

namespace {

std::string num(double x) {
  std::ostringstream s;
  s.precision(6);
  s << x;
  return s.str();
}

}  // namespace

void check_option_ranges(const MeshParams& job) {
  const std::string who = "job '" + job.name + "': ";
  auto positive_finite = [&](double v, const char* what) {
    if (!(std::isfinite(v) && v > 0)) throw UsageError(who + what + " " + num(v) + " must be finite and > 0");
  };
  positive_finite(job.scale, "scale (--scale)");
  positive_finite(job.sizing.max_size, "size (--size)");
  if (job.sizing.min_size != 0) positive_finite(job.sizing.min_size, "min_size (--min-size)");
  positive_finite(job.sizing.gradation, "gradation (--gradation)");
  if (!(job.sizing.gradation < kMaxGradation))
    throw UsageError(who + "gradation (--gradation) " + num(job.sizing.gradation) + " must be below " +
                     num(kMaxGradation) + ": an edge of length L leaving a zone of size s has the size s + g L / 2 " +
                     "at its midpoint, which L reaches only when g < 2, so no mesh could follow the field");
  if (!(std::isfinite(job.sharp_angle) && job.sharp_angle >= 0 && job.sharp_angle < 180))
    throw UsageError(who + "sharp_angle (--sharp-angle) " + num(job.sharp_angle) + " must be in [0, 180)");
  for (std::size_t i = 0; i < job.sizing.zones.size(); ++i) {
    const SizingZone& z = job.sizing.zones[i];
    const std::string w = who + "zones[" + std::to_string(i) + "]" + (z.name.empty() ? "" : " (" + z.name + ")") + ": ";
    if (!(std::isfinite(z.size) && z.size > 0)) throw UsageError(w + "size " + num(z.size) + " must be finite and > 0");
    for (double c : z.coords)
      if (!(std::isfinite(c) && std::fabs(c) <= kMaxLength))
        throw UsageError(w + "coordinate " + num(c) + " is outside [-" + num(kMaxLength) + ", " + num(kMaxLength) +
                         "] = +-2^120, where distances to it stay finite");
  }
}

ModelRanges check_model_ranges(const MeshParams& job, const SurfaceMesh& raw) {
  const double size = job.sizing.max_size;
  const bool given = job.sizing.min_size > 0 && job.sizing.min_size != size / 1000;  // not the default
  ModelRanges out{size, given ? job.sizing.min_size : size / 1000, {}};
  if (raw.points.size() == 0) return out;  // prepare_surface reports empty models
  double lo[3], hi[3], magnitude = 0;
  for (int k = 0; k < 3; ++k) lo[k] = hi[k] = raw.points.p(0)[k];
  for (std::size_t i = 0; i < raw.points.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const double v = raw.points.p(i)[k];
      lo[k] = std::min(lo[k], v);
      hi[k] = std::max(hi[k], v);
      magnitude = std::max(magnitude, std::fabs(v));
    }
  // In the scaled units (an overflow to inf is caught by the first check).
  const double s = job.scale;
  const double m = magnitude * s;
  const double d0 = hi[0] - lo[0], d1 = hi[1] - lo[1], d2 = hi[2] - lo[2];
  const double big = std::max({d0, d1, d2});
  const double extent = big > 0 ? big * std::sqrt((d0 / big) * (d0 / big) + (d1 / big) * (d1 / big) +
                                                  (d2 / big) * (d2 / big)) * s
                                 : 0;
  const std::string scaled = s != 1 ? " after scaling by " + num(s) : std::string();
  if (!(std::isfinite(m) && m <= kMaxLength))
    throw InputError(job.input, 0,
                     "coordinates up to " + num(magnitude) + scaled + " (" + num(m) + ") exceed " + num(kMaxLength) +
                         " = 2^120, the largest length the mesher computes with exactly and finitely; scale the model down (--scale)");
  if (big > 0 && !(extent >= kMinLength))
    throw InputError(job.input, 0,
                     "the model's extent (bounding-box diagonal) is " + num(extent) + scaled + ", below " +
                         num(kMinLength) + " = 2^-120, the smallest length the mesher computes with exactly and finitely; scale the model up (--scale)");
  if (big > 0 && m > kMaxMagnitudePerExtent * extent)
    throw InputError(job.input, 0,
                     "the model lies too far from the origin for its size: coordinates up to " + num(m) + scaled +
                         " are more than " + num(kMaxMagnitudePerExtent) + " = 2^21 times its extent (bounding-box diagonal) " +
                         num(extent) + ", and the rounding of points on its surface would exceed the mesh check's tolerance " +
                         "(1e-9 x the extent); move the model towards the origin");
  if (size > kMaxLength)
    throw UsageError("job '" + job.name + "': size (--size) " + num(size) + " is above " + num(kMaxLength) +
                     " = 2^120, the largest length the mesher computes with exactly and finitely");
  if (size > extent && extent > 0) {
    // No element is larger than the model: the size is the extent (and so is the default
    // min_size's base), whatever larger number was asked for.
    out.size = extent;
    if (!given) out.min_size = extent / 1000;
    out.note = "size " + num(size) + " is more than the model's extent (bounding-box diagonal) " + num(extent) +
               scaled + "; meshed at size " + num(extent) + ", the coarsest";
  }
  const double relative = kMinSizePerExtent * extent;
  const double floor = std::max(kMinLength, relative);
  const std::string why = relative >= kMinLength
                              ? " = 2^-22 times the model's extent" + scaled +
                                    ": tets that small would be thinner than the tolerance (1e-9 x the extent) at which the mesher takes them for flat"
                              : " = 2^-120, the smallest length the mesher computes with exactly and finitely";
  if (size < floor)
    throw UsageError("job '" + job.name + "': size (--size) " + num(size) + " is below " + num(floor) + why);
  if (given && out.min_size < floor)
    throw UsageError("job '" + job.name + "': min_size (--min-size) " + num(out.min_size) + " is below " + num(floor) + why);
  if (!given && out.min_size < floor) {
    out.note = "min_size raised from " + num(out.min_size) + " (size / 1000) to " + num(floor) + why;
    out.min_size = floor;
  }
  if (given && out.min_size > out.size) {
    out.min_size = out.size;
    out.note += ", and min_size with it";
  }
  return out;
}

}  // namespace kdmesh
