// Test support: the consistency of DelaunayStats' walk histogram.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "mesher/delaunay/delaunay.h"

namespace kdmesh::test {

/// Every walk's tests lie in its bin's range (kWalkBins), the bins' tests add up to
/// orient_tests, and the walks number between `min_walks` and `max_walks`.
inline void expect_walk_histogram_consistent(const DelaunayStats& st, std::uint64_t min_walks,
                                             std::uint64_t max_walks, const std::string& what) {
  std::uint64_t walks = 0, tests = 0;
  for (std::size_t b = 0; b < kWalkBins; ++b) {
    const std::uint64_t lo = b == 0 ? 0 : std::uint64_t(1) << (b - 1);
    EXPECT_GE(st.walk_tests[b], lo * st.walks[b]) << what << ", bin " << b;
    if (b + 1 < kWalkBins) {
      const std::uint64_t hi = b == 0 ? 0 : (std::uint64_t(1) << b) - 1;
      EXPECT_LE(st.walk_tests[b], hi * st.walks[b]) << what << ", bin " << b;
    }
    walks += st.walks[b];
    tests += st.walk_tests[b];
  }
  EXPECT_EQ(tests, st.orient_tests) << what;
  EXPECT_GE(walks, min_walks) << what;
  EXPECT_LE(walks, max_walks) << what;
}

}  // namespace kdmesh::test
