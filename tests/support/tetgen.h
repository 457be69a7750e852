// kdmesh tests — skipping what needs TetGen in a build without it (KDMESH_WITH_TETGEN=OFF).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <gtest/gtest.h>

#include "mesher/reference/reference_delaunay.h"

/// First statement of a test that runs TetGen (in-process or through the kdmesh executable,
/// which is the same build): skipped, with the reason, when this kdmesh has no TetGen.
#define KDMESH_REQUIRE_TETGEN()                                                        \
  do {                                                                                 \
    if (!kdmesh::tetgen_available()) GTEST_SKIP() << kdmesh::without_tetgen_message("this test"); \
  } while (0)
