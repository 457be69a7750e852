// kdmesh — the mutable tet structure of the quality-improvement pass (mesher/improve/improve_tets.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/improve/improve_tets.h"
#include "mesher/quality/centroid_sides.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <string>

#include "core/cpu_count.h"
#include "core/error.h"
#include "core/parallel_collect.h"
#include "core/parallel_for.h"
#include "core/uninit_allocator.h"
#include "mesher/bucket_scatter.h"
#include "mesher/volume/volume_mesh.h"

namespace kdmesh {

namespace {

using Key = std::array<std::uint32_t, 3>;

Key sorted_key(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  if (a > b) std::swap(a, b);
  if (b > c) std::swap(b, c);
  if (a > b) std::swap(a, b);
  return {a, b, c};
}

Key face_key(const std::uint32_t* v, int i) {
  return sorted_key(v[kTetFace[i][0]], v[kTetFace[i][1]], v[kTetFace[i][2]]);
}

}  // namespace

ImproveTets::ImproveTets(NodeSet& nodes, const std::vector<std::uint32_t>& tets,
                         const std::vector<std::uint32_t>& region, const std::vector<std::uint32_t>* adjacency)
    : nodes_(&nodes) {
  const std::size_t nt = tets.size() / 4, np = nodes.size_count();
  {  // the first reference past the nodes (each worker's first, then the least)
    std::vector<std::size_t> bad(available_cpus(), tets.size());
    parallel_for(4 * nt, [&](std::size_t b, std::size_t e, unsigned w) {
      for (std::size_t i = b; i < e && bad[w] == tets.size(); ++i)
        if (tets[i] >= np) bad[w] = i;
    }, 1 << 16);
    const std::size_t i = *std::min_element(bad.begin(), bad.end());
    if (i < tets.size())
      throw UsageError("improve_mesh: tet " + std::to_string(i / 4) + " references node " +
                       std::to_string(tets[i]) + " of " + std::to_string(np));
  }
  // Slots in the order of each tet's smallest vertex id (a counting sort; stable): the tets
  // around a vertex then lie close together in memory when nearby nodes have nearby ids,
  // which the passes' star walks (and the input order, in insertion order) need.
  std::vector<std::uint32_t, UninitAllocator<std::uint32_t>> order(nt);  // slot -> input tet (all written)
  bucket_scatter(
      nt, np,
      [&](std::size_t t) {
        return std::min(std::min(tets[4 * t], tets[4 * t + 1]), std::min(tets[4 * t + 2], tets[4 * t + 3]));
      },
      [&](std::size_t t, std::size_t at) { order[at] = std::uint32_t(t); });
  // Room for the slots the flip stage's pools add (take_slots, only with 64k tets or more
  // below its threshold; the paper gear box's 24.5M grew by 102k): growing an array past its
  // capacity doubled it and copied it, ~1 GB into fresh pages for all five on the gear box,
  // both copies resident at once. Pages of the room stay unresident until used.
  const std::size_t room = slot_room(nt);
  tv_.reserve(4 * room);
  ta_.reserve(4 * room);
  region_.reserve(room);
  version_.reserve(room);
  inside_known_.reserve(room);
  tv_.resize(4 * nt);
  ta_.resize(4 * nt);
  region_.resize(nt);
  version_.resize(nt);
  inside_known_.resize(nt);
  const bool given = adjacency && adjacency->size() == 4 * nt;
  parallel_for(nt, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t s = b; s < e; ++s) {
      std::copy_n(&tets[4 * std::size_t(order[s])], 4, &tv_[4 * s]);
      region_[s] = order[s] < region.size() ? region[order[s]] : 0;
      version_[s] = 0;
      inside_known_[s] = 0;
      if (!given) std::fill_n(&ta_[4 * s], 4, kImproveNone);
    }
  }, 1 << 16);
  // Room for the nodes the passes add (add_interior_node, add_boundary_node: 26 splits on the
  // paper gear box): the first one doubled and copied the node set's arrays, ~150 MB there.
  const std::size_t node_room = np + np / 64 + 64;
  nodes.reserve(node_room);
  vtet_.reserve(node_room);
  locked_.reserve(node_room);
  // Each node's tet: the last slot holding it (the largest), as a loop over the slots in
  // order would leave it.
  vtet_.assign(np, kImproveNone);
  parallel_for(nt, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t t = b; t < e; ++t)
      for (int i = 0; i < 4; ++i) {
        std::atomic_ref<std::uint32_t> at(vtet_[tv_[4 * t + i]]);
        std::uint32_t now = at.load(std::memory_order_relaxed);
        while ((now == kImproveNone || now < t) &&
               !at.compare_exchange_weak(now, std::uint32_t(t), std::memory_order_relaxed)) {
        }
      }
  }, 1 << 16);
  if (given) {
    // The given adjacency, in slots (a slot's vertices are its tet's, in the same order).
    std::vector<std::uint32_t> slot_of(nt);
    parallel_for(nt, [&](std::size_t b, std::size_t e, unsigned) {
      for (std::size_t s = b; s < e; ++s) slot_of[order[s]] = std::uint32_t(s);
    }, 1 << 16);
    parallel_for(nt, [&](std::size_t b, std::size_t e, unsigned) {
      for (std::size_t s = b; s < e; ++s)
        for (int i = 0; i < 4; ++i) {
          const std::uint32_t a = (*adjacency)[4 * std::size_t(order[s]) + i];
          ta_[4 * s + i] = a == kNoAdjacentTet ? kImproveNone : 4 * slot_of[a >> 2] + (a & 3);
        }
    }, 1 << 16);
  } else {
    match_faces(np);
  }
  lock_interfaces(np);
}

void ImproveTets::match_faces(std::size_t np) {
  const std::size_t nt = tv_.size() / 4;
  // Faces bucketed by their smallest vertex (counting sort), each bucket sorted by the two
  // other vertices, equal neighbours matched.
  struct Rec {
    std::uint32_t b, c, ref;
  };
  std::vector<Rec, UninitAllocator<Rec>> faces(4 * nt);  // written by the scatter, not zeroed first
  const std::vector<std::size_t> start = bucket_scatter(
      4 * nt, np, [&](std::size_t f) { return face_key(&tv_[4 * (f / 4)], int(f % 4))[0]; },
      [&](std::size_t f, std::size_t at) {
        const Key k = face_key(&tv_[4 * (f / 4)], int(f % 4));
        faces[at] = {k[1], k[2], std::uint32_t(f)};
      });
  std::vector<std::uint8_t> overfull(np, 0);
  parallel_for(np, [&](std::size_t kb, std::size_t ke, unsigned) {
  for (std::size_t k = kb; k < ke; ++k) {
    Rec* b = faces.data() + start[k];
    Rec* e = faces.data() + start[k + 1];
    std::sort(b, e, [](const Rec& x, const Rec& y) {
      return x.b != y.b ? x.b < y.b : x.c != y.c ? x.c < y.c : x.ref < y.ref;
    });
    for (Rec* x = b; x < e;) {
      Rec* y = x + 1;
      while (y < e && y->b == x->b && y->c == x->c) ++y;
      if (y - x > 2) overfull[k] = 1;
      if (y - x == 2) {
        ta_[x->ref] = x[1].ref;
        ta_[x[1].ref] = x->ref;
      }
      x = y;
    }
  }
  }, 4096);
  for (std::size_t k = 0; k < np; ++k)
    if (overfull[k])
      throw CheckError("improve_mesh: a face at node " + std::to_string(k) +
                       " is shared by more than two tets");
}

void ImproveTets::lock_interfaces(std::size_t np) {
  const std::size_t nt = tv_.size() / 4;
  // Interfaces between regions (touching bodies) are kept as they are: their nodes are locked.
  // (On all cores: a node's flag may be set by several threads, all to 1.)
  locked_.assign(np, 0);
  parallel_for(nt, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t t = b; t < e; ++t)
      for (int i = 0; i < 4; ++i) {
        const std::uint32_t r = ta_[4 * t + i];
        if (r == kImproveNone || region_[r >> 2] == region_[t]) continue;
        for (int j = 0; j < 3; ++j)
          std::atomic_ref<std::uint8_t>(locked_[tv_[4 * t + std::size_t(kTetFace[i][j])]])
              .store(1, std::memory_order_relaxed);
      }
  }, 1 << 16);
}

std::uint32_t ImproveTets::new_slot(std::vector<std::uint32_t>& from) {
  if (!from.empty()) {
    const std::uint32_t t = from.back();
    from.pop_back();
    inside_known_[t] = 0;
    return t;
  }
  const std::uint32_t t = std::uint32_t(tv_.size() / 4);
  tv_.insert(tv_.end(), 4, kImproveNone);
  ta_.insert(ta_.end(), 4, kImproveNone);
  region_.push_back(0);
  version_.push_back(0);
  inside_known_.push_back(0);
  return t;
}

std::vector<std::uint32_t> ImproveTets::take_slots(std::size_t n) {
  if (free_.size() < n) {
    const std::size_t grow = n - free_.size(), at = tv_.size() / 4;
    tv_.resize(tv_.size() + 4 * grow, kImproveNone);
    ta_.resize(ta_.size() + 4 * grow, kImproveNone);
    region_.resize(region_.size() + grow, 0);
    version_.resize(version_.size() + grow, 0);
    inside_known_.resize(inside_known_.size() + grow, 0);
    for (std::size_t k = grow; k-- > 0;) free_.push_back(std::uint32_t(at + k));
  }
  std::vector<std::uint32_t> pool(free_.end() - std::ptrdiff_t(n), free_.end());
  free_.resize(free_.size() - n);
  return pool;
}

void ImproveTets::give_slots(const std::vector<std::uint32_t>& pool) {
  free_.insert(free_.end(), pool.begin(), pool.end());
}

void ImproveTets::link_face(std::uint32_t t, int i, std::uint32_t ref) {
  ta_[4 * std::size_t(t) + i] = ref;
  if (ref != kImproveNone) ta_[ref] = 4 * t + std::uint32_t(i);
}

void ImproveTets::certify_inside() {
  if (!inside_query) return;
  // Every step on all cores (one thread took 0.5 s of the paper gear box's 23.6M tets), in
  // slot order: the tets with a surface vertex, their faces between them, their sides.
  const std::size_t nt = tv_.size() / 4;
  const std::vector<std::uint32_t> slots = parallel_collect(
      nt, [this](std::size_t t) { return alive(std::uint32_t(t)) && has_surface_vertex(v(std::uint32_t(t))); });
  const std::size_t ns = slots.size();
  SlotArray<std::uint32_t> sub_of(nt);
  parallel_for(nt, [&](std::size_t b, std::size_t e, unsigned) {
    std::fill(sub_of.begin() + std::ptrdiff_t(b), sub_of.begin() + std::ptrdiff_t(e), kImproveNone);
  }, 1 << 16);
  std::vector<std::uint32_t> sub_tets(4 * ns);
  parallel_for(ns, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t k = b; k < e; ++k) {
      sub_of[slots[k]] = std::uint32_t(k);
      std::copy_n(v(slots[k]), 4, &sub_tets[4 * k]);
    }
  }, 1 << 16);
  // The faces (4 k + i) of tet slots[k] whose tet across is a later one of them, and the pairs.
  auto across = [&](std::size_t f) { return adj(slots[f / 4], int(f % 4)); };
  const std::vector<std::uint32_t> faces = parallel_collect(4 * ns, [&](std::size_t f) {
    const std::uint32_t a = across(f);
    return a != kImproveNone && (a >> 2) > slots[f / 4] && sub_of[a >> 2] != kImproveNone;
  });
  std::vector<TetPair, UninitAllocator<TetPair>> pairs(faces.size());
  parallel_for(faces.size(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t j = b; j < e; ++j) pairs[j] = {faces[j] / 4, sub_of[across(faces[j]) >> 2]};
  }, 1 << 16);
  std::vector<std::uint32_t> sub_region;
  if (region_query)
    for (const std::uint32_t t : slots) sub_region.push_back(region_[t]);
  const std::vector<std::int8_t> side =
      region_query ? centroid_sides(nodes_->points, sub_tets, pairs, *inside_query, *region_query, sub_region)
                   : centroid_sides(nodes_->points, sub_tets, pairs, *inside_query);
  parallel_for(ns, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t k = b; k < e; ++k)
      if (side[k] == 1) inside_known_[slots[k]] = 1;
  }, 1 << 16);
}

bool ImproveTets::fresh_in_region(const std::vector<std::uint32_t>& fresh, std::uint32_t r) const {
  if (!region_query) return true;  // touching bodies: every new tet's centroid in the body
  for (std::size_t k = 0; k < fresh.size(); k += 4) {
    const double* q[4] = {p(fresh[k]), p(fresh[k + 1]), p(fresh[k + 2]), p(fresh[k + 3])};
    if (!region_ok(&fresh[k], q, r)) return false;
  }
  return true;
}

bool ImproveTets::replace(const std::vector<std::uint32_t>& old,
                          const std::vector<std::uint32_t>& fresh,
                          std::vector<std::uint32_t>* created, bool boundary_may_change,
                          bool regions_known, std::vector<std::uint32_t>* pool) {
  const std::size_t nn = fresh.size() / 4;
  if (pool && pool->size() + old.size() < nn) return false;  // the pool cannot hold them
  for (std::uint32_t t : old)
    if (region_[t] != region_[old[0]]) return false;  // the cavity would cross an interface
  // A face across to another tet of the cavity is inner. (A search of `old`, a few tets,
  // rather than per-slot marks: threads replacing disjoint cavities share no scratch.)
  auto in_old = [&old](std::uint32_t u) { return std::find(old.begin(), old.end(), u) != old.end(); };
  // Entries: the cavity's outer faces (source = the face reference across, or kImproveNone
  // for a boundary face; tag 0) and the new tets' faces (source = 4*k+i; tag 1).
  struct Entry {
    Key key;
    std::uint32_t src;
    std::uint8_t is_new;
  };
  static thread_local std::vector<Entry> e;
  e.clear();
  for (std::uint32_t t : old)
    for (int i = 0; i < 4; ++i) {
      const std::uint32_t r = ta_[4 * std::size_t(t) + i];
      if (r != kImproveNone && in_old(r >> 2)) continue;
      e.push_back({face_key(&tv_[4 * std::size_t(t)], i), r, 0});
    }
  if (!regions_known && !fresh_in_region(fresh, old.empty() ? 0 : region_[old[0]])) return false;
  for (std::size_t k = 0; k < nn; ++k)
    for (int i = 0; i < 4; ++i) e.push_back({face_key(&fresh[4 * k], i), std::uint32_t(4 * k + i), 1});
  // (The keys compared field by field: std::array's == is a memcmp call.)
  auto same = [](const Key& a, const Key& b) { return a[0] == b[0] && a[1] == b[1] && a[2] == b[2]; };
  std::sort(e.begin(), e.end(), [](const Entry& a, const Entry& b) {
    if (a.key[0] != b.key[0]) return a.key[0] < b.key[0];
    if (a.key[1] != b.key[1]) return a.key[1] < b.key[1];
    if (a.key[2] != b.key[2]) return a.key[2] < b.key[2];
    return a.is_new < b.is_new;
  });
  // Every key exactly twice, at least one of the two new; with boundary_may_change, a key
  // once: a new face (listed as a pair with itself: it becomes a boundary face), or a
  // boundary face of the cavity (left out: it goes away).
  static thread_local std::vector<Entry> pairs;
  pairs.clear();
  for (std::size_t x = 0; x < e.size();) {
    if (x + 1 < e.size() && same(e[x].key, e[x + 1].key)) {
      if (!e[x + 1].is_new || (x + 2 < e.size() && same(e[x + 2].key, e[x].key))) return false;
      pairs.push_back(e[x]);
      pairs.push_back(e[x + 1]);
      x += 2;
      continue;
    }
    if (!boundary_may_change || (!e[x].is_new && e[x].src != kImproveNone)) return false;
    if (e[x].is_new) pairs.push_back(e[x]), pairs.push_back(e[x]);
    ++x;
  }
  e.swap(pairs);

  static thread_local std::vector<std::uint32_t> slot;
  slot.assign(nn, 0);
  for (std::uint32_t t : old) {
    for (int i = 0; i < 4; ++i) {
      const std::uint32_t w = tv_[4 * std::size_t(t) + i];
      if (vtet_[w] == t) vtet_[w] = kImproveNone;
    }
    tv_[4 * std::size_t(t)] = kImproveNone;
    (pool ? *pool : free_).push_back(t);
  }
  const std::uint32_t reg = old.empty() ? 0 : region_[old[0]];
  for (std::size_t k = 0; k < nn; ++k) {
    const std::uint32_t t = new_slot(pool ? *pool : free_);
    slot[k] = t;
    for (int i = 0; i < 4; ++i) {
      tv_[4 * std::size_t(t) + i] = fresh[4 * k + i];
      ta_[4 * std::size_t(t) + i] = kImproveNone;
      vtet_[fresh[4 * k + i]] = t;
    }
    region_[t] = reg;
    ++version_[t];
  }
  for (std::size_t x = 0; x < e.size(); x += 2) {
    const Entry &a = e[x], &b = e[x + 1];  // b is new
    const std::uint32_t tb = slot[b.src >> 2];
    const int ib = int(b.src & 3);
    if (a.is_new && a.src == b.src) continue;  // a new boundary face: stays kImproveNone
    if (a.is_new) {
      const std::uint32_t ta = slot[a.src >> 2];
      ta_[4 * std::size_t(tb) + ib] = 4 * ta + (a.src & 3);
      ta_[4 * std::size_t(ta) + (a.src & 3)] = 4 * tb + std::uint32_t(ib);
    } else {
      link_face(tb, ib, a.src);
    }
  }
  if (created) *created = slot;
  return true;
}

std::uint32_t ImproveTets::add_interior_node(const double* p, float h) {
  nodes_->push_back(p, NodeKind::interior, kNoFacet, h);
  vtet_.push_back(kImproveNone);
  locked_.push_back(0);
  return std::uint32_t(nodes_->size_count() - 1);
}

std::uint32_t ImproveTets::add_boundary_node(const double* p, NodeKind kind, std::uint32_t facet, float h) {
  nodes_->push_back(p, kind, facet, h);
  vtet_.push_back(kImproveNone);
  locked_.push_back(0);
  return std::uint32_t(nodes_->size_count() - 1);
}

bool ImproveTets::remove(std::uint32_t t, std::uint32_t may_orphan) {
  const std::uint32_t* tv = &tv_[4 * std::size_t(t)];
  for (int i = 0; i < 4; ++i) {  // a face on an interface stays one
    const std::uint32_t r = ta_[4 * std::size_t(t) + i];
    if (r != kImproveNone && region_[r >> 2] != region_[t]) return false;
  }
  // Each vertex w of t needs a neighbour tet (across a face of t holding w) to stand for it.
  std::uint32_t stand_in[4];
  for (int i = 0; i < 4; ++i) {
    stand_in[i] = kImproveNone;
    for (int f = 0; f < 4 && stand_in[i] == kImproveNone; ++f)
      if (f != i && ta_[4 * std::size_t(t) + f] != kImproveNone) stand_in[i] = ta_[4 * std::size_t(t) + f] >> 2;
    if (stand_in[i] == kImproveNone && tv[i] != may_orphan) return false;
  }
  for (int i = 0; i < 4; ++i) {
    const std::uint32_t r = ta_[4 * std::size_t(t) + i];
    if (r != kImproveNone) ta_[r] = kImproveNone;
    if (vtet_[tv[i]] == t) vtet_[tv[i]] = stand_in[i];
  }
  tv_[4 * std::size_t(t)] = kImproveNone;
  ++version_[t];
  free_.push_back(t);
  return true;
}

void ImproveTets::star(std::uint32_t v, std::vector<std::uint32_t>& out) const {
  // Thread-safe (no shared marks). "Seen" is a small open-addressing set on the stack (a star
  // has a few dozen tets; a larger one falls back to scanning `out`).
  constexpr std::uint32_t kSlots = 256, kEmpty = 0xFFFFFFFFu;
  std::uint32_t seen[kSlots];
  std::fill(seen, seen + kSlots, kEmpty);
  auto insert = [&](std::uint32_t u) {  // true if u was not there
    if (out.size() >= kSlots / 2) {
      if (std::find(out.begin(), out.end(), u) != out.end()) return false;
      out.push_back(u);
      return true;
    }
    for (std::uint32_t h = (u * 0x9E3779B1u) >> 24;; h = (h + 1) & (kSlots - 1)) {
      if (seen[h] == u) return false;
      if (seen[h] == kEmpty) {
        seen[h] = u;
        out.push_back(u);
        // Read when its turn in the walk comes: by then the lines are there, the waits for
        // the tets found meanwhile overlapping instead of coming one after another.
        __builtin_prefetch(&tv_[4 * std::size_t(u)]);
        __builtin_prefetch(&ta_[4 * std::size_t(u)]);
        return true;
      }
    }
  };
  out.clear();
  const std::uint32_t t0 = vtet_[v];
  if (t0 == kImproveNone) return;
  insert(t0);
  for (std::size_t k = 0; k < out.size(); ++k) {
    const std::uint32_t t = out[k];
    for (int i = 0; i < 4; ++i) {
      if (tv_[4 * std::size_t(t) + i] == v) continue;  // the face opposite v does not hold v
      const std::uint32_t r = ta_[4 * std::size_t(t) + i];
      if (r != kImproveNone) insert(r >> 2);
    }
  }
}

namespace {

/// The two vertices of tet v other than a and b, in the order (c, d) for which (a, b, c, d)
/// has the tet's orientation. False if a or b is not a vertex of v.
bool other_two(const std::uint32_t* v, std::uint32_t a, std::uint32_t b, std::uint32_t& c,
               std::uint32_t& d) {
  const int ia = index_in(v, a), ib = index_in(v, b);
  if (ia < 0 || ib < 0) return false;
  int o[2], k = 0;
  for (int i = 0; i < 4; ++i)
    if (i != ia && i != ib) o[k++] = i;
  // (a, b, v[o0], v[o1]) has the orientation of the tet iff the permutation is even.
  const int perm[4] = {ia, ib, o[0], o[1]};
  int inv = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) inv += perm[i] > perm[j];
  c = v[o[0]], d = v[o[1]];
  if (inv & 1) std::swap(c, d);
  return true;
}

}  // namespace

bool ImproveTets::edge_ring(std::uint32_t t, std::uint32_t a, std::uint32_t b,
                            std::vector<std::uint32_t>& ring,
                            std::vector<std::uint32_t>& tets) const {
  std::uint32_t c, d;
  if (!ring_start(t, a, b, ring, tets, c, d)) return false;
  std::uint32_t cur = t;
  for (int guard = 0; guard < 256; ++guard) {
    ring.push_back(c);
    tets.push_back(cur);
    if (!turn(cur, c, d)) return false;
    if (cur == t) return true;
  }
  return false;
}

bool ImproveTets::ring_start(std::uint32_t t, std::uint32_t a, std::uint32_t b,
                             std::vector<std::uint32_t>& ring, std::vector<std::uint32_t>& tets,
                             std::uint32_t& c, std::uint32_t& d) const {
  ring.clear();
  tets.clear();
  return other_two(&tv_[4 * std::size_t(t)], a, b, c, d);
}

bool ImproveTets::turn(std::uint32_t& cur, std::uint32_t& c, std::uint32_t& d) const {
  const std::uint32_t r = ta_[4 * std::size_t(cur) + index_in(&tv_[4 * std::size_t(cur)], c)];
  if (r == kImproveNone) return false;
  cur = r >> 2;
  c = d;
  d = tv_[4 * std::size_t(cur) + (r & 3)];
  return true;
}

bool ImproveTets::open_edge_ring(std::uint32_t t, std::uint32_t a, std::uint32_t b, int max_ring,
                                 std::vector<std::uint32_t>& ring,
                                 std::vector<std::uint32_t>& tets) const {
  std::uint32_t c, d;
  if (!ring_start(t, a, b, ring, tets, c, d)) return false;
  // Backwards (across the face (a, b, c), opposite d) to the tet with the first boundary face.
  std::uint32_t cur = t;
  for (int guard = 0;; ++guard) {
    if (guard > max_ring) return false;
    if (!turn(cur, d, c)) break;  // (the roles swapped: across the face opposite d)
    if (cur == t) return false;  // closed ring
  }
  // Forwards (across (a, b, d), opposite c) to the other boundary face.
  for (int guard = 0;; ++guard) {
    if (guard >= max_ring) return false;
    ring.push_back(c);
    tets.push_back(cur);
    if (!turn(cur, c, d)) {
      ring.push_back(d);
      return true;
    }
  }
}

void ImproveTets::prefetch_around(std::uint32_t t) const {
  const std::uint32_t* tv = tv_.data();
  const std::uint32_t* ta = ta_.data();
  const std::uint32_t* v = tv + 4 * std::size_t(t);
  std::uint32_t near[4];
  int n = 0;
  for (int i = 0; i < 4; ++i) {
    __builtin_prefetch(p(v[i]));
    const std::uint32_t r = ta[4 * std::size_t(t) + i];
    if (r == kImproveNone) continue;
    near[n++] = r;
    __builtin_prefetch(tv + 4 * std::size_t(r >> 2));
    __builtin_prefetch(ta + 4 * std::size_t(r >> 2));
  }
  // Each level's loads wait for the one before, all of its lines at once.
  std::uint32_t far[12];
  int f = 0;
  for (int k = 0; k < n; ++k) {
    const std::uint32_t u = near[k] >> 2;
    __builtin_prefetch(p(tv[4 * std::size_t(u) + (near[k] & 3)]));  // u's vertex off t
    for (int j = 0; j < 4; ++j) {
      const std::uint32_t r = ta[4 * std::size_t(u) + j];
      if (j == int(near[k] & 3) || r == kImproveNone) continue;
      far[f++] = r;
      __builtin_prefetch(tv + 4 * std::size_t(r >> 2));
      __builtin_prefetch(ta + 4 * std::size_t(r >> 2));
    }
  }
  for (int k = 0; k < f; ++k) __builtin_prefetch(p(tv[4 * std::size_t(far[k] >> 2) + (far[k] & 3)]));
}

std::size_t ImproveTets::write_back(VolumeMesh& mesh) const {
  const std::size_t cap = tv_.size() / 4, np = nodes_->size_count();
  // Live slots are numbered in slot order, nodes in id order. The slots go in fixed chunks on
  // all threads: each chunk's live count (then its first number), its boundary faces, and the
  // nodes it uses; the results are those of one loop over the slots.
  constexpr std::size_t kChunk = std::size_t(1) << 16;
  const std::size_t chunks = (cap + kChunk - 1) / kChunk;
  // Boundary faces (in the old numbering): key, tet, outward vertices.
  struct BFace {
    Key key;
    std::uint32_t tet;
    std::array<std::uint32_t, 3> out;
  };
  std::vector<std::uint32_t> new_id(np, kImproveNone), first(chunks + 1, 0);
  std::vector<std::vector<BFace>> faces(chunks);
  parallel_for(chunks, [&](std::size_t cb, std::size_t ce, unsigned) {
    for (std::size_t c = cb; c < ce; ++c) {
      std::uint32_t live = 0;
      for (std::size_t t = c * kChunk; t < std::min(cap, (c + 1) * kChunk); ++t) {
        if (tv_[4 * t] == kImproveNone) continue;
        const std::uint32_t* v = &tv_[4 * t];
        for (int i = 0; i < 4; ++i) {
          std::atomic_ref<std::uint32_t>(new_id[v[i]]).store(0, std::memory_order_relaxed);  // used
          if (ta_[4 * t + i] == kImproveNone)  // (live: the chunk's number, made global below)
            faces[c].push_back({face_key(v, i), live, {v[kTetFace[i][0]], v[kTetFace[i][1]], v[kTetFace[i][2]]}});
        }
        ++live;
      }
      first[c + 1] = live;
    }
  }, 1);
  for (std::size_t c = 0; c < chunks; ++c) first[c + 1] += first[c];
  const std::uint32_t nt = first[chunks];
  std::uint32_t nn = 0;
  for (std::size_t i = 0; i < np; ++i)
    if (new_id[i] != kImproveNone) new_id[i] = nn++;
  std::vector<BFace> now;
  for (std::size_t c = 0; c < chunks; ++c)
    for (BFace f : faces[c]) {
      f.tet += first[c];
      now.push_back(f);
    }
  std::vector<std::vector<BFace>>().swap(faces);
  std::sort(now.begin(), now.end(), [](const BFace& a, const BFace& b) { return a.key < b.key; });
  std::vector<std::uint8_t> used(now.size(), 0);
  std::vector<std::uint32_t> boundary, boundary_tet;
  boundary.reserve(3 * now.size());
  boundary_tet.reserve(now.size());
  std::size_t kept = 0;
  for (std::size_t f = 0; f + 2 < mesh.boundary.size(); f += 3) {
    const Key k = sorted_key(mesh.boundary[f], mesh.boundary[f + 1], mesh.boundary[f + 2]);
    auto it = std::lower_bound(now.begin(), now.end(), k,
                               [](const BFace& a, const Key& key) { return a.key < key; });
    if (it == now.end() || it->key != k || used[std::size_t(it - now.begin())]) continue;
    used[std::size_t(it - now.begin())] = 1;
    ++kept;
    for (int j = 0; j < 3; ++j) boundary.push_back(new_id[mesh.boundary[f + j]]);
    boundary_tet.push_back(it->tet);
  }
  const std::size_t changed = (mesh.boundary.size() / 3 - kept) + (now.size() - kept);
  for (std::size_t x = 0; x < now.size(); ++x) {
    if (used[x]) continue;
    for (int j = 0; j < 3; ++j) boundary.push_back(new_id[now[x].out[j]]);
    boundary_tet.push_back(now[x].tet);
  }
  // Tets and regions, on all threads, into the mesh's own arrays (the tets the pass started
  // from: their pages are already there, and no other array of 16 bytes a tet is made).
  std::vector<std::uint32_t>& tets = mesh.tets;
  std::vector<std::uint32_t>& region = mesh.tet_region;
  tets.resize(4 * std::size_t(nt));
  region.resize(nt);
  parallel_for(chunks, [&](std::size_t cb, std::size_t ce, unsigned) {
    for (std::size_t c = cb; c < ce; ++c) {
      std::size_t k = first[c];
      for (std::size_t t = c * kChunk; t < std::min(cap, (c + 1) * kChunk); ++t) {
        if (tv_[4 * t] == kImproveNone) continue;
        for (int i = 0; i < 4; ++i) tets[4 * k + i] = new_id[tv_[4 * t + i]];
        region[k++] = region_[t];
      }
    }
  }, 1);
  // Nodes (compacted in id order).
  NodeSet out;
  out.points.xyz.reserve(3 * std::size_t(nn));
  for (std::size_t i = 0; i < np; ++i)
    if (new_id[i] != kImproveNone)
      out.push_back(nodes_->points.p(std::uint32_t(i)), nodes_->kind[i], nodes_->facet[i],
                    nodes_->size[i]);
  std::vector<std::uint32_t>().swap(mesh.tet_adj);  // the tets changed
  mesh.boundary = std::move(boundary);
  mesh.boundary_tet = std::move(boundary_tet);
  mesh.nodes = std::move(out);
  return changed;
}

}  // namespace kdmesh
