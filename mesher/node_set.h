// kdmesh — mesh nodes with their kind and target size (pipeline data: NodeSet).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <vector>

#include "core/point_set.h"

namespace kdmesh {

/// What a node lies on. Values are written to files (VTU point data "node_kind").
enum class NodeKind : std::uint8_t {
  corner = 0,    ///< a feature corner (surface point where feature edges meet or end)
  edge = 1,      ///< on a feature edge
  surface = 2,   ///< on the surface, off features
  interior = 3,  ///< inside the solid
};

/// Nodes, struct-of-arrays; node i is points.p(i).
struct NodeSet {
  PointSet points;
  std::vector<NodeKind> kind;
  std::vector<std::uint32_t> facet;  ///< a surface facet the node lies on; kNoFacet if interior
  std::vector<float> size;           ///< target size h at the node

  std::size_t size_count() const { return kind.size(); }
  /// Room for n nodes in every array: push_back up to n nodes moves none.
  void reserve(std::size_t n) {
    points.xyz.reserve(3 * n);
    kind.reserve(n);
    facet.reserve(n);
    size.reserve(n);
  }
  void push_back(const double* p, NodeKind k, std::uint32_t f, float h) {
    points.push_back(p[0], p[1], p[2]);
    kind.push_back(k);
    facet.push_back(f);
    size.push_back(h);
  }
};

}  // namespace kdmesh
