// kdmesh — sharp feature detection (STUB: no features; the real implementation replaces this).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "sizing/features.h"

namespace kdmesh {

FeatureEdges detect_sharp_edges(const SurfaceMesh&, double) { return {}; }

}  // namespace kdmesh
