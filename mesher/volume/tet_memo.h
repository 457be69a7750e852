// kdmesh — answers of exact queries about tets, kept by the tets' vertex ids from one boundary
// recovery round to the next (used by the volume mesher).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

namespace kdmesh {

/// An int32 answer per tet, keyed by the tet's four vertex ids in their stored order. The
/// recovery's side and region queries take a tet's centroid summed in that order, so the key
/// is order-sensitive: a tet stored in another order could round to another centroid, and is
/// asked again. An answer depends only on the nodes (ids, positions, kinds) and the surface, so
/// a memo stays valid while the node ids do (rounds that only add Steiner points) and must be
/// cleared when they change.
///
/// Open addressing with linear probing, at most 5/8 full, in parts chosen by the keys' hashes
/// so that put() fills each part on its own thread. The contents do not depend on the thread
/// count.
class TetMemo {
 public:
  /// A tet (its index in a triangulation) and the answer found for it.
  struct Asked {
    std::uint32_t tet;
    std::int32_t answer;
  };
  static constexpr std::int32_t kNone = std::numeric_limits<std::int32_t>::min();

  /// The answer put for the tet with vertex ids v[0..3], or kNone. Safe to call from several
  /// threads at once (with no put meanwhile).
  std::int32_t find(const std::uint32_t* v) const;

  /// Puts answer(k) for the tet with vertex ids key(k), k in [0, n); a tet put before gets the
  /// new answer. No vertex id may be 0xFFFFFFFF (the infinite vertex: never asked about).
  /// `key` and `answer` are called from several threads at once.
  void put(std::size_t n, const std::function<const std::uint32_t*(std::size_t)>& key,
           const std::function<std::int32_t(std::size_t)>& answer);

  void clear();
  std::size_t size() const;

 private:
  struct Slot {
    std::uint32_t v[4];  // v[0] == kFree: a free slot
    std::int32_t answer;
  };
  struct Part {
    std::vector<Slot> slots;  // a power of two, or none
    std::size_t size = 0;
  };
  static constexpr std::uint32_t kFree = 0xFFFFFFFFu;
  static constexpr unsigned kPartBits = 3;  // 8 parts
  static std::uint64_t hash(const std::uint32_t* v);
  static void insert(Part& p, const std::uint32_t* v, std::int32_t answer, std::uint64_t h);
  /// Grows part p to room for `more` further keys, rehashing what it holds.
  static void reserve(Part& p, std::size_t more);
  std::vector<Part> parts_ = std::vector<Part>(std::size_t(1) << kPartBits);
};

}  // namespace kdmesh
