// kdmesh — the paper's seven point distributions (Fig. 6), deterministic for a seed.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/point_set.h"

namespace kdmesh {

enum class Distribution { cube, planes, paraboloid, spiral, disk, cylinder, axes };

/// "cube", "planes", "paraboloid", "spiral", "disk", "cylinder", "axes"; throws UsageError.
Distribution parse_distribution(std::string_view name);
std::string_view distribution_name(Distribution d);
std::vector<Distribution> all_distributions();

/// n points of distribution `d`, each disturbed slightly off its geometric model, in the
/// unit cube [0,1]^3 (roughly). Same (d, n, seed) => bit-identical output on any platform.
PointSet generate_points(Distribution d, std::size_t n, std::uint64_t seed);

}  // namespace kdmesh
