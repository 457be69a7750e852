// kdmesh — a multi-level hash grid of nodes with local sizes, for spacing (conflict) queries.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <array>
#include <cstdint>
#include <vector>

namespace kdmesh {

/// Nodes p_i with local sizes h_i (> 0). Two nodes conflict when
///   |p - q| < beta * (h_p + h_q) / 2
/// (beta given per query). Node i is stored at the level l whose scale s_l = s0 * 2^l
/// satisfies s_l <= h_i < 2 s_l (level 0 also takes every h_i < s0), in cells 4 s_l across,
/// so a query scans a few cells per non-empty level whatever the size range (cells s_l
/// across made 3-4 cells per axis to probe, mostly empty: node placement took 1.5x longer
/// on bench_placement's boxes and cylinder, surface sampling 2.3x). Cells live in an
/// open-addressing hash table keyed by (level, cell ix, iy, iz); each cell is a singly
/// linked list of node ids.
/// Single-threaded; lengths in model units.
class SpacingGrid {
 public:
  /// lo: a corner below every point that will be inserted (xyz); s0: finest cell size (> 0).
  SpacingGrid(const double* lo, double s0);

  /// Adds node (p, h); returns its id in this grid (0, 1, 2, ... in insertion order).
  std::uint32_t insert(const double* p, double h);
  /// Declares that every h given to insert() and conflicts() is a value of one size field
  /// that is g-Lipschitz (|h(p) - h(q)| <= g |p - q|; kdmesh's sizing fields are, with g their
  /// gradation). A query can then skip a whole level of small nodes: a node q with h_q < 2 s
  /// is at least (h - h_q) / g from p, beyond reach when h is large. Without it, a query with
  /// h = 3 scans ~18^3 empty cells of the level of h = 0.15 (minutes on a refined block).
  /// It also bounds h_q and |p - q| of a conflicting node when g beta / 2 < 1, so levels of
  /// larger nodes are skipped too and no level scans farther than that bound.
  void set_lipschitz(double g) { lipschitz_ = g; }
  /// True if some stored node q conflicts with (p, h) for this beta (see above).
  bool conflicts(const double* p, double h, double beta) const;
  std::size_t size() const { return node_.size(); }
  /// Room for `nodes` nodes in all: inserts up to that many do not move the stored ones
  /// (a doubling vector copied every node record into fresh pages each time it grew).
  void reserve(std::size_t nodes) { node_.reserve(nodes); }
  const double* lo() const { return lo_; }
  double s0() const { return s0_; }

 private:
  static constexpr int kLevels = 31;
  /// Index of the level's cell holding coordinate x (along an axis, model units minus lo_),
  /// clamped to the table's range: insert() and conflicts() both go through it.
  std::int64_t cell_index(double x, int level) const;
  std::uint64_t key_cells(int level, std::int64_t i, std::int64_t j, std::int64_t k) const;
  std::uint32_t find(std::uint64_t key) const;  // head node of the cell, or kEmpty
  /// True if a node of cell (i, j, k) of `level` conflicts with (p, h).
  bool cell_conflicts(int level, std::int64_t i, std::int64_t j, std::int64_t k, const double* p, double h,
                      double beta) const;
  void grow();
  int level_of(double h) const;

  static constexpr std::uint32_t kEmpty = 0xffffffffu;
  double lo_[3];
  double s0_;
  std::array<double, kLevels> scale_;     // s0 2^l: level l holds the nodes of s_l <= h < 2 s_l
  std::array<double, kLevels> inv_cell_;  // 1 / (its cells' width, 4 s_l)
  /// A node's position, size and the next node of its cell, in one record: a query reads
  /// them together (three arrays cost three cache misses per node visited).
  struct Node {
    double p[3];
    double h;
    std::uint32_t next;
  };
  std::vector<Node> node_;
  /// Hash table slot: a cell's key (0 = empty slot; keys are never 0) and its first node, in
  /// one record (a probe reads both), packed into 12 bytes as the two arrays it replaced were
  /// (a 16-byte slot is a third more table memory).
  struct [[gnu::packed]] Slot {
    std::uint64_t key;
    std::uint32_t head;
  };
  std::vector<Slot> slots_;
  std::size_t used_ = 0;
  std::uint32_t level_mask_ = 0;       // bit l set when level l holds a node
  double lipschitz_ = 0;               // 0: unknown (no level is skipped)
};

}  // namespace kdmesh
