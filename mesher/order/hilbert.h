// kdmesh — 3D Hilbert curve keys (private to mesher/ and its tests).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/point_set.h"

namespace kdmesh::hilbert {

/// Bits per axis of the quantisation grid used for point orders: 2^21 cells per axis,
/// 3 * 21 = 63-bit keys.
inline constexpr int kBits = 21;

/// Spreads the low 21 bits of v so that bit b moves to bit 3b.
inline std::uint64_t spread3(std::uint32_t v) {
  std::uint64_t x = v & 0x1fffffu;
  x = (x | (x << 32)) & 0x001f00000000ffffULL;
  x = (x | (x << 16)) & 0x001f0000ff0000ffULL;
  x = (x | (x << 8)) & 0x100f00f00f00f00fULL;
  x = (x | (x << 4)) & 0x10c30c30c30c30c3ULL;
  x = (x | (x << 2)) & 0x1249249249249249ULL;
  return x;
}

/// Hilbert index of the cell (x, y, z) of a 2^bits grid per axis (1 <= bits <= 21,
/// coordinates < 2^bits), in [0, 8^bits). Skilling's transpose method ("Programming the
/// Hilbert curve", AIP Conf. Proc. 707, 2004): the cell coordinates are transformed in
/// place into the "transposed" Hilbert index, whose bits are then interleaved with x
/// most significant. A bijection of the grid onto [0, 8^bits) in which cells with
/// consecutive indices share a face.
inline std::uint64_t key(std::uint32_t x, std::uint32_t y, std::uint32_t z, int bits = kBits) {
  std::uint32_t X[3] = {x, y, z};
  const std::uint32_t M = std::uint32_t(1) << (bits - 1);
  // Inverse undo: from the top bit Q down, for each axis i: if bit Q of X[i] is set, invert
  // the bits of X[0] below Q, else exchange the bits below Q of X[0] and X[i]. Written
  // without branches (the bits are unpredictable; branches would dominate the cost).
  for (std::uint32_t Q = M; Q > 1; Q >>= 1) {
    const std::uint32_t P = Q - 1;
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t set = std::uint32_t(0) - ((X[i] & Q) != 0);  // all ones if set
      const std::uint32_t t = (X[0] ^ X[i]) & P & ~set;                // exchange mask
      X[0] ^= (P & set) | t;
      X[i] ^= t;  // for i == 0, t == 0
    }
  }
  // Gray encode.
  X[1] ^= X[0];
  X[2] ^= X[1];
  std::uint32_t t = 0;
  for (std::uint32_t Q = M; Q > 1; Q >>= 1) t ^= (Q - 1) & (std::uint32_t(0) - ((X[2] & Q) != 0));
  X[0] ^= t;
  X[1] ^= t;
  X[2] ^= t;
  // Interleave: bit b of X[0], X[1], X[2] become key bits 3b+2, 3b+1, 3b.
  return (spread3(X[0]) << 2) | (spread3(X[1]) << 1) | spread3(X[2]);
}

/// The same as key() for kBatch cells at once, lane by lane (the loops over lanes
/// vectorise; one key alone is a long dependency chain). x, y, z are overwritten.
inline constexpr int kBatch = 16;
inline void key_batch(std::uint32_t* x, std::uint32_t* y, std::uint32_t* z, std::uint64_t* out,
                      int bits = kBits) {
  const std::uint32_t M = std::uint32_t(1) << (bits - 1);
  for (std::uint32_t Q = M; Q > 1; Q >>= 1) {
    const std::uint32_t P = Q - 1;
    for (int l = 0; l < kBatch; ++l) {  // i = 0: invert or (no-op) exchange
      x[l] ^= P & (std::uint32_t(0) - ((x[l] & Q) != 0));
    }
    for (int l = 0; l < kBatch; ++l) {  // i = 1
      const std::uint32_t set = std::uint32_t(0) - ((y[l] & Q) != 0);
      const std::uint32_t t = (x[l] ^ y[l]) & P & ~set;
      x[l] ^= (P & set) | t;
      y[l] ^= t;
    }
    for (int l = 0; l < kBatch; ++l) {  // i = 2
      const std::uint32_t set = std::uint32_t(0) - ((z[l] & Q) != 0);
      const std::uint32_t t = (x[l] ^ z[l]) & P & ~set;
      x[l] ^= (P & set) | t;
      z[l] ^= t;
    }
  }
  for (int l = 0; l < kBatch; ++l) {
    y[l] ^= x[l];
    z[l] ^= y[l];
  }
  std::uint32_t t[kBatch] = {};
  for (std::uint32_t Q = M; Q > 1; Q >>= 1) {
    for (int l = 0; l < kBatch; ++l) t[l] ^= (Q - 1) & (std::uint32_t(0) - ((z[l] & Q) != 0));
  }
  for (int l = 0; l < kBatch; ++l) {
    out[l] = (spread3(x[l] ^ t[l]) << 2) | (spread3(y[l] ^ t[l]) << 1) | spread3(z[l] ^ t[l]);
  }
}

/// Keys of all points, quantised over the bounding CUBE of the set: origin = lower corner
/// of the bounding box, side = its largest extent (the same scale on every axis), 2^21
/// cells per axis. A zero side (all points equal) maps every point to cell (0,0,0).
std::vector<std::uint64_t> point_keys(const PointSet& points);

/// Sorts ids[0..count) by (keys[id], id) (a total order: the result does not depend on
/// the initial arrangement of ids).
void sort_ids_by_key(std::uint32_t* ids, std::size_t count, const std::uint64_t* keys);

}  // namespace kdmesh::hilbert
