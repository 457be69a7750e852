// kdmesh — the paper's seven point distributions (Fig. 6), and two node sets standing in
// for its practical "constrained cube" models (Sect. 3.3), all deterministic for a seed.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/point_set.h"

namespace kdmesh {

enum class Distribution {
  cube, planes, paraboloid, spiral, disk, cylinder, axes,  // the paper's seven (Fig. 6)
  constrained_cube,          // graded FE-like nodes, fine near three edges (Tables 16-17)
  refined_constrained_cube,  // constrained_cube plus 20% midpoints (emulates Table 17)
};

/// "cube", "planes", "paraboloid", "spiral", "disk", "cylinder", "axes", "constrained-cube",
/// "refined-constrained-cube"; throws UsageError.
Distribution parse_distribution(std::string_view name);
std::string_view distribution_name(Distribution d);
/// The paper's seven distributions of Fig. 6, in the paper's order (not the practical ones).
std::vector<Distribution> all_distributions();
/// The two tool-generated stand-ins for the paper's practical models (Sect. 3.3):
/// constrained_cube, refined_constrained_cube. Definitions in distributions.cpp.
std::vector<Distribution> practical_distributions();

/// n points of distribution `d`, each disturbed slightly off its geometric model, in the
/// unit cube [0,1]^3 (roughly; the practical ones exactly, in [0,1)^3). Same (d, n, seed)
/// => bit-identical output on any platform.
PointSet generate_points(Distribution d, std::size_t n, std::uint64_t seed);

}  // namespace kdmesh
