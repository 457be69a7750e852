// kdmesh — FeMesh validation and the entity / group indexes the solver-format writers share.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "io/fe_mesh_index.h"

#include <algorithm>
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

}  // namespace kdmesh
