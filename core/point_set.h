// kdmesh — plain point data shared by every pipeline stage.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace kdmesh {

/// A set of points in R^3, stored flat: xyz[3*i + 0..2] are the coordinates of point i.
/// Point ids are uint32_t indices into this array; every stage refers to points by id.
struct PointSet {
  std::vector<double> xyz;  ///< 3*n doubles

  std::size_t size() const { return xyz.size() / 3; }
  bool empty() const { return xyz.empty(); }
  const double* p(std::uint32_t i) const { return xyz.data() + 3 * std::size_t(i); }
  void push_back(double x, double y, double z) {
    xyz.push_back(x);
    xyz.push_back(y);
    xyz.push_back(z);
  }
};

/// Index of the first point with a NaN or infinite coordinate, or size() if all are finite.
std::size_t first_non_finite(const PointSet& points);

/// The exponent k for which points * 2^k have their largest |coordinate| in [0.5, 1), or 0
/// when that scaling would underflow a non-zero coordinate below the smallest normal double
/// (or the set is empty or all zero). Multiplying by 2^k is then exact, so every orientation
/// and insphere sign, and hence every Delaunay tetrahedralization, is unchanged; only the
/// magnitudes move to where volumes and third-party tolerances behave (e.g. 1e+-200 inputs).
int unit_scale_exponent(const PointSet& points);

/// The exponent k that brings the largest |coordinate| into [0.5, 1) (0 for none or non-finite
/// ones), even when the smallest coordinates then lose low bits or underflow: for
/// floating-point measures such as volumes, which must neither overflow nor lose the largest
/// terms, and are compared with a relative tolerance anyway.
int magnitude_scale_exponent(const PointSet& points);

/// points * 2^exponent, coordinate by coordinate (std::ldexp; exact for unit_scale_exponent).
PointSet scaled_copy(const PointSet& points, int exponent);

/// The points at unit scale: a rescaled copy when unit_scale_exponent asks for one, otherwise
/// the input itself (no copy in the common case). The input must outlive this object.
class UnitScaled {
 public:
  explicit UnitScaled(const PointSet& points)
      : input_(&points), exponent_(unit_scale_exponent(points)) {
    if (exponent_ != 0) copy_ = scaled_copy(points, exponent_);
  }
  const PointSet& points() const { return exponent_ != 0 ? copy_ : *input_; }
  int exponent() const { return exponent_; }

 private:
  const PointSet* input_;
  int exponent_;
  PointSet copy_;
};

}  // namespace kdmesh
