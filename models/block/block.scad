// kdmesh — the constrained block: a 100 mm cube, [0,100]^3 (mm).
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Regenerate with models/generate.sh (do not edit block.stl by hand). The three constrained
// edges (refined by block.yaml's fixed_edges zones; see docs/models.md) are the mutually skew
//   A: y = 0,   z = 0,   x in [0,100]
//   B: x = 100, z = 100, y in [0,100]
//   C: x = 0,   y = 100, z in [0,100]
cube([100, 100, 100]);
