// kdmesh — the ranges of a job's numbers inside which the pipeline is exact and finite; a job
// outside them is refused with an error naming the option, before any work that could trap,
// overflow or loop without bound.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include "core/surface_mesh.h"
#include "tools/lib/mesh_job.h"

namespace kdmesh {

/// Largest |coordinate| of the scaled model and of every zone. Two limits, the lower wins:
///  - finiteness: the pipeline evaluates, in double precision before any exact fallback,
///    polynomials of degree up to 10 in coordinates (radius ratios of the quality measures:
///    squared lengths times degree-5 insphere terms; products of CGAL's squared distances), so
///    |x| <= 1e30 keeps every such value below 1e300 and no inf or NaN reaches GMP (which
///    traps: SIGFPE) or a loop bound;
///  - resolution: from 2^52 = 4.5e15 up a double has no fractional bits, and node placement
///    then loses nodes (found by ExtremeNumbers.SweepGivesCorrectMeshOrClearError: a unit cube
///    scaled by 6e15 or 1e16 and meshed at its coarsest size lost 2 of its 8 corners, exit 4 /
///    5; by 4e15 and below it meshed correctly). 2^50 = 1.13e15 keeps a factor 4 of margin.
constexpr double kMaxCoordinate = 1125899906842624.0;  // 2^50
/// Smallest extent (bounding-box diagonal) of the scaled model: degree-10 values of its
/// coordinate differences stay above 1e-300, clear of the subnormal range (2.2e-308) where
/// relative precision is lost and divisions by underflowed lengths give inf.
constexpr double kMinExtent = 1e-30;
/// Largest size relative to the model's extent. A size of the extent already gives the
/// coarsest mesh; beyond 1e3 times it, size * extent-scale products (densities, distances
/// to far-away sample points, the interior fill's steps) leave the range above.
constexpr double kMaxSizePerExtent = 1e3;
/// Smallest min_size relative to the model's largest |coordinate| (or extent, if larger):
/// nodes spaced by it must be distinct doubles with room to spare, 2^-40 = 9.1e-13 (12 bits
/// above the double's 2^-52 resolution); it also keeps every node-count estimate below
/// (2^40)^3 = 1.3e36, finite and printable.
constexpr double kMinSizePerMagnitude = 9.094947017729282e-13;
/// Largest gradation. Two bounds meet here. What a mesh can honour: at gradation g, the size
/// one element length s away from a zone of size s is (1 + g) s, so above 2 neighbouring
/// elements would differ by more than 3x, which no tetrahedral mesh of bounded quality gives.
/// What the surface sampling costs: its sweep (mesher/surface_sampling.cpp) splits facets until
/// g D <= h / 2, so its work per surface node grows as g^2: measured on the block at size 10,
/// node placement takes 0.10 s at g = 1, 0.25 s at 2, 0.45 s at 3, 2.9 s at 5, 11.6 s at 10,
/// and minutes at 50 (it did not end: issue 19).
constexpr double kMaxGradation = 2;

/// Checks the job's option values alone (before reading anything): size, min_size, gradation,
/// scale and sharp_angle finite and in range; zone sizes, coordinates and radii finite and
/// within kMaxCoordinate. UsageError (exit 2) naming the option.
void check_option_ranges(const MeshJob& job);

/// Checks the model once read, after scaling (before it is prepared): every coordinate times
/// job.scale within kMaxCoordinate, the extent at least kMinExtent, and size / min_size
/// against the extent and magnitude. InputError (exit 3) naming the file for coordinates,
/// UsageError (exit 2) naming the option for sizes.
void check_model_ranges(const MeshJob& job, const SurfaceMesh& raw);

}  // namespace kdmesh
