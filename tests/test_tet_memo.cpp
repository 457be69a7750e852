// kdmesh — TetMemo (mesher/volume/tet_memo.h), the recovery rounds' memo of tets' answers, and
// label_regions with it: answers found again by the tet's ordered vertex ids, and the labels
// of a round that reads them equal to those of asking again.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <vector>

#include "core/rng.h"
#include "mesher/delaunay/delaunay.h"
#include "mesher/order/order.h"
#include "mesher/volume/interface_faces.h"
#include "mesher/volume/tet_memo.h"
#include "tests/support/touching_boxes.h"

namespace kdmesh {
namespace {

using Quad = std::array<std::uint32_t, 4>;

void put_all(TetMemo& memo, const std::vector<Quad>& keys, const std::vector<std::int32_t>& answers) {
  memo.put(keys.size(), [&](std::size_t k) { return keys[k].data(); }, [&](std::size_t k) { return answers[k]; });
}

TEST(TetMemo, FindsEachAnswerByTheOrderedVertexIds) {
  Rng rng(3);
  TetMemo memo;
  std::map<Quad, std::int32_t> truth;
  std::vector<Quad> keys;
  std::vector<std::int32_t> answers;
  // Several puts (the memo grows between them), ids dense and sparse, answers of any sign.
  for (int round = 0; round < 4; ++round) {
    keys.clear();
    answers.clear();
    for (int k = 0; k < 60000; ++k) {
      const std::uint32_t span = round % 2 ? 0xFFFFFFF0u : 5000;
      const Quad q{std::uint32_t(rng.below(span)), std::uint32_t(rng.below(span)), std::uint32_t(rng.below(span)),
                   std::uint32_t(rng.below(span))};
      const std::int32_t a = std::int32_t(rng.below(2000)) - 1000;
      keys.push_back(q);
      answers.push_back(a);
      truth[q] = a;  // a key put twice keeps the later answer
    }
    put_all(memo, keys, answers);
  }
  ASSERT_EQ(memo.size(), truth.size());
  std::size_t rotated_absent = 0;
  for (const auto& [q, a] : truth) {
    ASSERT_EQ(memo.find(q.data()), a);
    const Quad r{q[1], q[2], q[3], q[0]};  // the same tet in another order is another key
    if (!truth.count(r)) {
      EXPECT_EQ(memo.find(r.data()), TetMemo::kNone);
      ++rotated_absent;
    }
  }
  EXPECT_GT(rotated_absent, truth.size() / 2);
  for (int k = 0; k < 1000; ++k) {
    const Quad q{std::uint32_t(rng.below(5000)) + 5000, 1, 2, 3};  // never put (ids >= 5000 only in sparse rounds)
    if (!truth.count(q)) {
      EXPECT_EQ(memo.find(q.data()), TetMemo::kNone);
    }
  }
  memo.clear();
  EXPECT_EQ(memo.size(), 0u);
  EXPECT_EQ(memo.find(truth.begin()->first.data()), TetMemo::kNone);
}

// label_regions on two touching boxes: a call that reads the answers and node regions of an
// earlier one asks nothing and labels every tet as asking again does.
TEST(TetMemo, LabelRegionsFromTheMemoEqualsAskingAgain) {
  const test::TouchingBoxes boxes;
  const Domain domain = boxes.domain();
  // Jittered lattice nodes, those on the interface x = 1 surface-kind: tets across it have
  // nodes of both bodies and ask for their centroids.
  NodeSet nodes;
  Rng rng(11);
  const int m = 8;
  for (int i = 0; i <= 2 * m; ++i)
    for (int j = 0; j <= m; ++j)
      for (int k = 0; k <= m; ++k) {
        double p[3] = {double(i) / m, double(j) / m, double(k) / m};
        const bool boundary = i == 0 || i == 2 * m || j == 0 || j == m || k == 0 || k == m || i == m;
        if (!boundary)
          for (double& x : p) x += rng.uniform(-0.2, 0.2) / m;
        nodes.push_back(p, boundary ? NodeKind::surface : NodeKind::interior, kNoFacet, float(1.0 / m));
      }
  const DelaunayResult dr = delaunay(nodes.points, make_order(nodes.points, {}));
  const Triangulation& tri = dr.tri;
  std::vector<std::uint8_t> inside(tri.num_tets());
  for (std::size_t t = 0; t < tri.num_tets(); ++t) inside[t] = !tri.is_infinite(t);

  std::size_t q0 = 0;
  const std::vector<std::uint32_t> plain = label_regions(tri, nodes, domain, inside, &q0);
  TetMemo memo;
  std::vector<TetMemo::Asked> asked;
  std::vector<std::int32_t> node_regions;
  std::size_t q1 = 0;
  EXPECT_EQ(label_regions(tri, nodes, domain, inside, &q1, &memo, &asked, &node_regions), plain);
  EXPECT_EQ(q1, q0);
  ASSERT_GT(asked.size(), 10u);  // tets across the interface were asked
  EXPECT_EQ(node_regions.size(), nodes.size_count());
  memo.put(asked.size(), [&](std::size_t k) { return &tri.data[8 * std::size_t(asked[k].tet)]; },
           [&](std::size_t k) { return asked[k].answer; });
  std::size_t q2 = 0;
  std::vector<TetMemo::Asked> asked_again;
  EXPECT_EQ(label_regions(tri, nodes, domain, inside, &q2, &memo, &asked_again, &node_regions), plain);
  EXPECT_EQ(q2, 0u);
  EXPECT_TRUE(asked_again.empty());
  // The memo is read, not ignored: a wrong answer in it changes a label (a tet of the first
  // wave whose own answer is its label: no later wave revisits it).
  const TetMemo::Asked* first = nullptr;
  for (const TetMemo::Asked& a : asked)
    if (!first && a.answer >= 0 && plain[a.tet] == std::uint32_t(a.answer)) first = &a;
  ASSERT_NE(first, nullptr);
  memo.put(1, [&](std::size_t) { return &tri.data[8 * std::size_t(first->tet)]; },
           [&](std::size_t) { return 1 - first->answer; });
  std::size_t q3 = 0;
  EXPECT_NE(label_regions(tri, nodes, domain, inside, &q3, &memo, nullptr, &node_regions), plain);
}

}  // namespace
}  // namespace kdmesh
