// kdmesh — FeMesh validation and the entity / group indexes the solver-format writers share.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "io/fe_mesh_index.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <unordered_set>
#include <utility>

#include "core/error.h"

namespace kdmesh {

namespace {

const char* element_word(int d) { return d == 3 ? "tet" : d == 2 ? "face" : "edge"; }
const char* array_word(int d) { return d == 3 ? "tets" : d == 2 ? "faces" : "edges"; }
const char* entity_word(int d) {
  return d == 3 ? "tet_entity" : d == 2 ? "face_entity" : "edge_entity";
}

bool valid_name_char(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' ||
         c == '-';
}

/// Builds ids, start and element_of of one dimension (entities = the element -> entity array).
void bucket_elements(const std::vector<std::uint32_t>& entities, EntityTable& t) {
  // Distinct ids: elements of one entity usually come in runs, so the set sees few lookups.
  std::unordered_set<std::uint32_t> seen;
  bool have_last = false;
  std::uint32_t last = 0;
  for (const std::uint32_t e : entities) {
    if (have_last && e == last) continue;
    seen.insert(e);
    last = e;
    have_last = true;
  }
  t.ids.assign(seen.begin(), seen.end());
  std::sort(t.ids.begin(), t.ids.end());

  // Counting sort of the elements by entity position (stable: ascending element index).
  std::vector<std::uint32_t> pos(entities.size());
  std::size_t k = 0;
  have_last = false;
  for (std::size_t i = 0; i < entities.size(); ++i) {
    if (!have_last || entities[i] != last) {
      k = t.find(entities[i]);
      last = entities[i];
      have_last = true;
    }
    pos[i] = std::uint32_t(k);
  }
  t.start.assign(t.ids.size() + 1, 0);
  for (const std::uint32_t p : pos) ++t.start[p + 1];
  for (std::size_t j = 0; j < t.ids.size(); ++j) t.start[j + 1] += t.start[j];
  t.element_of.resize(entities.size());
  std::vector<std::size_t> fill(t.start.begin(), t.start.end() - 1);
  for (std::size_t i = 0; i < entities.size(); ++i) t.element_of[fill[pos[i]]++] = std::uint32_t(i);
}

/// Open-addressing table from sorted corner triples to slots 0..n-1.
class TriangleTable {
 public:
  explicit TriangleTable(std::size_t expected) {
    std::size_t cap = 16;
    while (cap < 2 * expected) cap *= 2;
    keys_.assign(cap, Key{kEmpty, 0, 0});
    vals_.assign(cap, 0);
  }
  /// The slot of {a, b, c} (sorted), inserting it as `next` if new; `inserted` tells which.
  std::uint32_t insert(const std::array<std::uint32_t, 3>& k, std::uint32_t next, bool& inserted) {
    std::size_t i = hash(k) & (keys_.size() - 1);
    while (keys_[i].a != kEmpty) {
      if (keys_[i].a == k[0] && keys_[i].b == k[1] && keys_[i].c == k[2]) {
        inserted = false;
        return vals_[i];
      }
      i = (i + 1) & (keys_.size() - 1);
    }
    keys_[i] = Key{k[0], k[1], k[2]};
    vals_[i] = next;
    inserted = true;
    return next;
  }
  /// The slot of {a, b, c} (sorted), or kEmpty.
  std::uint32_t find(const std::array<std::uint32_t, 3>& k) const {
    std::size_t i = hash(k) & (keys_.size() - 1);
    while (keys_[i].a != kEmpty) {
      if (keys_[i].a == k[0] && keys_[i].b == k[1] && keys_[i].c == k[2]) return vals_[i];
      i = (i + 1) & (keys_.size() - 1);
    }
    return kEmpty;
  }
  static constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();

 private:
  struct Key {
    std::uint32_t a, b, c;
  };
  static std::size_t hash(const std::array<std::uint32_t, 3>& k) {
    std::uint64_t h = std::uint64_t(k[0]) * 0x9E3779B97F4A7C15ull;
    h ^= (h >> 29) ^ (std::uint64_t(k[1]) * 0xC2B2AE3D27D4EB4Full);
    h ^= (h >> 31) ^ (std::uint64_t(k[2]) * 0x165667B19E3779F9ull);
    return std::size_t(h ^ (h >> 33));
  }
  std::vector<Key> keys_;
  std::vector<std::uint32_t> vals_;
};

/// True if (f0, f1, f2) is a cyclic rotation of (p, q, r).
bool same_cycle(const std::uint32_t* f, std::uint32_t p, std::uint32_t q, std::uint32_t r) {
  return (f[0] == p && f[1] == q && f[2] == r) || (f[0] == q && f[1] == r && f[2] == p) ||
         (f[0] == r && f[1] == p && f[2] == q);
}

}  // namespace

std::size_t EntityTable::find(std::uint32_t id) const {
  const auto it = std::lower_bound(ids.begin(), ids.end(), id);
  return it != ids.end() && *it == id ? std::size_t(it - ids.begin()) : ids.size();
}

FeIndex index_fe_mesh(const FeMesh& mesh, const char* who) {
  const std::string w = std::string(who) + ": ";
  if (mesh.order != 1 && mesh.order != 2)
    throw UsageError(w + "mesh order is " + std::to_string(mesh.order) + ", must be 1 or 2");
  const std::size_t np = mesh.points.size();
  if (mesh.points.xyz.size() % 3 != 0)
    throw UsageError(w + "points.xyz has " + std::to_string(mesh.points.xyz.size()) +
                     " values, not a multiple of 3");
  if (np > std::numeric_limits<std::uint32_t>::max())
    throw UsageError(w + "more than 2^32 - 1 points");
  for (std::size_t i = 0; i < mesh.points.xyz.size(); ++i)
    if (!std::isfinite(mesh.points.xyz[i]))
      throw UsageError(w + "point " + std::to_string(i / 3) + " has a non-finite coordinate");

  FeIndex index;
  for (int d = 1; d <= 3; ++d) {
    const auto& conn = connectivity(mesh, d);
    const auto& ent = entity_array(mesh, d);
    const std::size_t nn = std::size_t(nodes_per_element(mesh, d));
    if (conn.size() % nn != 0)
      throw UsageError(w + array_word(d) + " has " + std::to_string(conn.size()) +
                       " node ids, not a multiple of " + std::to_string(nn) + " (order " +
                       std::to_string(mesh.order) + ")");
    const std::size_t n = conn.size() / nn;
    if (ent.size() != n)
      throw UsageError(w + entity_word(d) + " has " + std::to_string(ent.size()) +
                       " values for " + std::to_string(n) + " " + array_word(d));
    if (n >= std::numeric_limits<std::uint32_t>::max())
      throw UsageError(w + "too many " + std::string(array_word(d)) + " (" + std::to_string(n) +
                       ")");
    for (std::size_t i = 0; i < conn.size(); ++i)
      if (conn[i] >= np)
        throw UsageError(w + element_word(d) + " " + std::to_string(i / nn) +
                         " references point " + std::to_string(conn[i]) + ", but the mesh has " +
                         std::to_string(np) + " points");
    bucket_elements(ent, index.dim[d]);
  }

  // Groups: names, dimensions, entities; then the entity -> groups lists.
  std::array<std::vector<std::pair<std::uint32_t, std::uint32_t>>, 4> pairs;  // (entity pos, group)
  std::array<std::unordered_set<std::string>, 4> names;
  for (std::size_t g = 0; g < mesh.groups.size(); ++g) {
    const FeGroup& grp = mesh.groups[g];
    const std::string gname = "group " + std::to_string(g) + " '" + grp.name + "'";
    if (grp.dim < 1 || grp.dim > 3)
      throw UsageError(w + gname + " has dim " + std::to_string(grp.dim) + ", must be 1, 2 or 3");
    if (grp.name.empty()) throw UsageError(w + "group " + std::to_string(g) + " has no name");
    for (const char c : grp.name)
      if (!valid_name_char(c))
        throw UsageError(w + "group " + std::to_string(g) + " name '" + grp.name +
                         "' has a character outside [A-Za-z0-9_-]");
    if (!names[grp.dim].insert(grp.name).second)
      throw UsageError(w + "two groups of dim " + std::to_string(grp.dim) + " are named '" +
                       grp.name + "'");
    if (grp.entities.empty()) throw UsageError(w + gname + " lists no entities");
    const EntityTable& t = index.dim[grp.dim];
    for (const std::uint32_t e : grp.entities) {
      const std::size_t k = t.find(e);
      if (k == t.size())
        throw UsageError(w + gname + " (dim " + std::to_string(grp.dim) + ") lists entity " +
                         std::to_string(e) + ", which has no " + array_word(grp.dim));
      pairs[grp.dim].emplace_back(std::uint32_t(k), std::uint32_t(g));
    }
  }
  for (int d = 1; d <= 3; ++d) {
    auto& p = pairs[d];
    std::sort(p.begin(), p.end());
    p.erase(std::unique(p.begin(), p.end()), p.end());
    EntityTable& t = index.dim[d];
    t.gstart.assign(t.size() + 1, 0);
    for (const auto& [k, g] : p) ++t.gstart[k + 1];
    for (std::size_t j = 0; j < t.size(); ++j) t.gstart[j + 1] += t.gstart[j];
    t.group_of.resize(p.size());
    for (std::size_t i = 0; i < p.size(); ++i) t.group_of[i] = p[i].second;  // p sorted by k
  }
  return index;
}

std::vector<std::uint32_t> group_nodes(const FeMesh& mesh, const FeIndex& index, std::size_t g) {
  const FeGroup& grp = mesh.groups[g];
  const EntityTable& t = index.dim[grp.dim];
  const auto& conn = connectivity(mesh, grp.dim);
  const std::size_t nn = std::size_t(nodes_per_element(mesh, grp.dim));
  std::vector<std::size_t> ks;
  std::size_t refs = 0;
  for (const std::uint32_t e : grp.entities) {
    const std::size_t k = t.find(e);
    ks.push_back(k);
    refs += t.num_elements(k) * nn;
  }
  std::sort(ks.begin(), ks.end());
  ks.erase(std::unique(ks.begin(), ks.end()), ks.end());

  const std::size_t np = mesh.points.size();
  std::vector<std::uint32_t> out;
  if (refs > np / 16) {
    // Many references: one bit per point, then the set bits in order (O(refs + np / 64)).
    std::vector<std::uint64_t> bits((np + 63) / 64, 0);
    for (const std::size_t k : ks)
      for (std::size_t j = t.start[k]; j < t.start[k + 1]; ++j) {
        const std::uint32_t* el = conn.data() + std::size_t(t.element_of[j]) * nn;
        for (std::size_t i = 0; i < nn; ++i) bits[el[i] >> 6] |= std::uint64_t(1) << (el[i] & 63);
      }
    for (std::size_t wi = 0; wi < bits.size(); ++wi)
      for (std::uint64_t b = bits[wi]; b; b &= b - 1)
        out.push_back(std::uint32_t(wi * 64 + std::size_t(__builtin_ctzll(b))));
  } else {
    out.reserve(refs);
    for (const std::size_t k : ks)
      for (std::size_t j = t.start[k]; j < t.start[k + 1]; ++j) {
        const std::uint32_t* el = conn.data() + std::size_t(t.element_of[j]) * nn;
        out.insert(out.end(), el, el + nn);
      }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }
  return out;
}

GroupFaceOwners match_group_faces(const FeMesh& mesh, const FeIndex& index, const int (&local_faces)[4][3],
                                  const char* who, const char* purpose) {
  constexpr std::uint32_t kNoSlot = GroupFaceOwners::kNoSlot;
  GroupFaceOwners out;
  const EntityTable& ft = index.dim[2];
  const std::size_t nf = mesh.num_faces();
  const std::size_t fn = std::size_t(mesh.face_nodes());
  out.slot_of_face.assign(nf, kNoSlot);

  std::size_t grouped = 0;
  for (std::size_t k = 0; k < ft.size(); ++k)
    if (ft.gstart[k + 1] > ft.gstart[k]) grouped += ft.num_elements(k);
  if (grouped == 0) return out;
  static_assert(kNoSlot == TriangleTable::kEmpty);

  // Slots: one per distinct corner triple of a grouped face; rep = its first face.
  TriangleTable table(grouped);
  std::vector<std::uint32_t> rep;
  std::vector<std::uint64_t> marked((mesh.points.size() + 63) / 64, 0);
  for (std::size_t k = 0; k < ft.size(); ++k) {
    if (ft.gstart[k + 1] == ft.gstart[k]) continue;
    for (std::size_t j = ft.start[k]; j < ft.start[k + 1]; ++j) {
      const std::uint32_t f = ft.element_of[j];
      const std::uint32_t* c = mesh.faces.data() + std::size_t(f) * fn;
      bool inserted;
      const std::uint32_t s =
          table.insert(sorted3(c[0], c[1], c[2]), std::uint32_t(rep.size()), inserted);
      if (inserted) rep.push_back(f);
      out.slot_of_face[f] = s;
      for (int i = 0; i < 3; ++i) marked[c[i] >> 6] |= std::uint64_t(1) << (c[i] & 63);
    }
  }
  out.tet.assign(rep.size(), kNoSlot);
  out.face.assign(rep.size(), 0);
  std::vector<std::uint8_t> outward(rep.size(), 0);

  auto is_marked = [&](std::uint32_t v) { return (marked[v >> 6] >> (v & 63)) & 1; };
  const std::size_t tn = std::size_t(mesh.tet_nodes());
  const std::size_t nt = mesh.num_tets();
  for (std::size_t t = 0; t < nt; ++t) {
    const std::uint32_t* c = mesh.tets.data() + t * tn;
    const bool m[4] = {bool(is_marked(c[0])), bool(is_marked(c[1])), bool(is_marked(c[2])),
                       bool(is_marked(c[3]))};
    if (int(m[0]) + int(m[1]) + int(m[2]) + int(m[3]) < 3) continue;
    for (int l = 0; l < 4; ++l) {
      const int* fc = local_faces[l];
      if (!m[fc[0]] || !m[fc[1]] || !m[fc[2]]) continue;
      const std::uint32_t s = table.find(sorted3(c[fc[0]], c[fc[1]], c[fc[2]]));
      if (s == kNoSlot) continue;
      // The listing turns inward, so the face is outward for this tet when its corners come
      // in the reverse cyclic order.
      const std::uint32_t* f = mesh.faces.data() + std::size_t(rep[s]) * fn;
      const bool out_of_this = same_cycle(f, c[fc[0]], c[fc[2]], c[fc[1]]);
      if (out.tet[s] == kNoSlot || (out_of_this && !outward[s])) {
        out.tet[s] = std::uint32_t(t);
        out.face[s] = std::uint8_t(l);
        outward[s] = out_of_this;
      }
    }
  }
  for (std::size_t f = 0; f < nf; ++f) {
    const std::uint32_t s = out.slot_of_face[f];
    if (s == kNoSlot || out.tet[s] != kNoSlot) continue;
    const std::uint32_t* c = mesh.faces.data() + f * fn;
    const std::size_t k = ft.find(mesh.face_entity[f]);
    throw UsageError(std::string(who) + ": face " + std::to_string(f) + " (points " + std::to_string(c[0]) +
                     " " + std::to_string(c[1]) + " " + std::to_string(c[2]) + ", entity " +
                     std::to_string(mesh.face_entity[f]) + ", group '" +
                     mesh.groups[ft.group_of[ft.gstart[k]]].name + "') is not a face of any tet, so it cannot be part of " +
                     purpose);
  }
  return out;
}

}  // namespace kdmesh
