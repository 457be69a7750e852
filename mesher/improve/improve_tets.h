// kdmesh — the mutable tet structure of the quality-improvement pass: flat arrays of 4 vertices
// and 4 face neighbours per tet, a free list, and the cavity replacement every operation uses.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <vector>

#include "core/uninit_allocator.h"
#include "mesher/node_set.h"
#include "mesher/surface/region_query.h"
#include "mesher/surface/surface_query.h"

namespace kdmesh {

struct VolumeMesh;

/// Tets of a mesh being improved. Face i of tet t is the face opposite tv[4t+i]; ta[4t+i] is
/// 4*u+j when that face is face j of tet u, kImproveNone when it is a boundary face (the mesh
/// is a domain: every face has at most one other tet). A dead tet has tv[4t] == kImproveNone
/// and its slot is on the free list. Every live tet is positively oriented.
inline constexpr std::uint32_t kImproveNone = 0xFFFFFFFFu;

/// Vertex slots of face i of a tet (the face opposite slot i), outward for a positively
/// oriented tet (mesh_check's order).
inline constexpr int kTetFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
/// Vertex slots of a tet's six edges.
inline constexpr int kTetEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

class ImproveTets {
 public:
  /// Builds the face adjacency of `tets` (4 ids into `nodes` per tet, positively oriented;
  /// every face in at most two tets, else CheckError) with one region id per tet. `nodes` is
  /// referenced, not copied: moved vertices are written to it. `adjacency`, if given with 4
  /// entries per tet (VolumeMesh::tet_adj), is taken as that adjacency instead of matching
  /// the faces.
  ImproveTets(NodeSet& nodes, const std::vector<std::uint32_t>& tets,
              const std::vector<std::uint32_t>& region,
              const std::vector<std::uint32_t>* adjacency = nullptr);

  NodeSet& nodes() { return *nodes_; }
  const NodeSet& nodes() const { return *nodes_; }
  const double* p(std::uint32_t v) const { return nodes_->points.p(v); }
  double* p_mut(std::uint32_t v) { return nodes_->points.xyz.data() + 3 * std::size_t(v); }

  std::size_t capacity() const { return tv_.size() / 4; }  ///< slots, live or dead
  /// Slots the slot arrays hold without moving, for a mesh of `tets` tets: room for the flip
  /// stage's pools (take_slots), which per-slot arrays kept beside these (SineCache) keep too.
  static std::size_t slot_room(std::size_t tets) { return tets + tets / 32; }
  std::size_t live() const { return tv_.size() / 4 - free_.size(); }
  bool alive(std::uint32_t t) const { return tv_[4 * std::size_t(t)] != kImproveNone; }
  const std::uint32_t* v(std::uint32_t t) const { return &tv_[4 * std::size_t(t)]; }
  std::uint32_t adj(std::uint32_t t, int i) const { return ta_[4 * std::size_t(t) + i]; }
  std::uint32_t region(std::uint32_t t) const { return region_[t]; }
  /// Vertex v lies on a face between two regions (an interface of touching bodies): it does not
  /// move. (replace() and remove() refuse to change such faces: every cavity is in one region.)
  bool locked(std::uint32_t v) const { return locked_[v] != 0; }
  /// A live tet incident to vertex v (kImproveNone if v is in no tet).
  std::uint32_t vertex_tet(std::uint32_t v) const { return vtet_[v]; }
  /// Bumped whenever the slot is (re)used: lets queues drop stale entries.
  std::uint32_t version(std::uint32_t t) const { return version_[t]; }

  /// Replaces the tets `old` (a connected cavity) by `fresh` (4 vertex ids per tet, positively
  /// oriented, filling the same region), all of region `region`. Faces are matched by vertex
  /// set: every face of a new tet must be either a face of another new tet or a face of the
  /// cavity's outer boundary. With `boundary_may_change`, a boundary face of the cavity may
  /// also go unmatched (it is no longer a face) and so may a new face (it becomes a boundary
  /// face): the caller has checked the new boundary. Returns false (and changes nothing) if
  /// the faces do not match. New tet ids are written to *created (if given).
  /// With `regions_known`, the caller has found fresh_in_region(fresh, region of old[0]) true
  /// (the flip stage tests it on its worker threads).
  /// With `pool` (dead slots from take_slots), the old slots go to it and the new tets take
  /// theirs from it (false, changing nothing, if it cannot hold them): threads may then
  /// replace at once cavities that share no tet and whose outer faces' tets are not in another
  /// thread's cavity, each with its own pool.
  bool replace(const std::vector<std::uint32_t>& old, const std::vector<std::uint32_t>& fresh,
               std::vector<std::uint32_t>* created = nullptr, bool boundary_may_change = false,
               bool regions_known = false, std::vector<std::uint32_t>* pool = nullptr);
  /// n dead slots taken off the free list (the slot arrays grow if it is shorter), for
  /// replace's `pool`; give_slots puts a pool's slots back on it.
  std::vector<std::uint32_t> take_slots(std::size_t n);
  void give_slots(const std::vector<std::uint32_t>& pool);
  /// region_ok for every tet of `fresh` (4 ids per tet) in region r: replace()'s test that new
  /// tets stay in the cavity's body. Thread-safe (reads only).
  bool fresh_in_region(const std::vector<std::uint32_t>& fresh, std::uint32_t r) const;

  /// Appends an interior node at p (target size h) to the node set and returns its id; it is
  /// in no tet until a replace() uses it.
  std::uint32_t add_interior_node(const double* p, float h);
  /// Appends a surface or edge node (kind) at p, a point of surface facet `facet`, likewise.
  std::uint32_t add_boundary_node(const double* p, NodeKind kind, std::uint32_t facet, float h);
  /// Removes tet t from the domain: its faces shared with other tets become boundary faces.
  /// Returns false (and changes nothing) if a vertex of t is in no other tet through those
  /// faces (it would be left without a tet), unless that vertex is `may_orphan`: it is then
  /// left unused (write_back drops it). The caller decides whether the new boundary is
  /// acceptable (mesher/improve/improve_caps.h).
  bool remove(std::uint32_t t, std::uint32_t may_orphan = kImproveNone);
  /// The live tets incident to v, by a walk over face neighbours from vertex_tet(v).
  /// Thread-safe (reads only), as are v(), adj(), p().
  void star(std::uint32_t v, std::vector<std::uint32_t>& out) const;

  /// The ring of edge (a, b) found from tet t (which must contain a and b): ring vertices r_0..
  /// r_{m-1} and tets such that tet k is (a, b, r_k, r_{k+1 mod m}) positively oriented.
  /// Returns false if the edge is on the boundary (the ring is open).
  bool edge_ring(std::uint32_t t, std::uint32_t a, std::uint32_t b,
                 std::vector<std::uint32_t>& ring, std::vector<std::uint32_t>& tets) const;
  /// The open ring of a boundary edge (a, b) found from tet t (which must contain a and b):
  /// ring vertices r_0..r_m and m tets such that tet k is (a, b, r_k, r_{k+1}) positively
  /// oriented, (a, b, r_0) and (a, b, r_m) the two boundary faces at the edge. Returns false
  /// if the edge is not on the boundary (the ring closes) or its ring is longer than max_ring.
  bool open_edge_ring(std::uint32_t t, std::uint32_t a, std::uint32_t b, int max_ring,
                      std::vector<std::uint32_t>& ring, std::vector<std::uint32_t>& tets) const;
  /// Starts loading what the rings of t's edges read (a hint; changes nothing): the tets
  /// across t's faces and the tets across theirs, which hold most of those rings, and the
  /// positions of their vertices. Without it each step around a ring waits for memory in turn.
  void prefetch_around(std::uint32_t t) const;
  /// Starts loading tet t's vertices, neighbours and version (a hint; changes nothing).
  void prefetch_tet(std::uint32_t t) const {
    __builtin_prefetch(&tv_[4 * std::size_t(t)]);
    __builtin_prefetch(&ta_[4 * std::size_t(t)]);
    __builtin_prefetch(&version_[t]);
  }

  /// The solid's surface, when set: a tet the pass creates (or changes by moving a vertex) with
  /// a vertex on the surface must have its centroid strictly inside the solid (exact ray
  /// parity), the rule of mesh_check. Such tets can lie across a curved or rough surface,
  /// which no orientation test sees (regression: tori failed the mesh check after the pass).
  /// One surface vertex is enough since surface nodes slide on curved surfaces: femur.ply at
  /// diag/40 got a tet of one surface and three interior vertices outside the solid.
  const SurfaceQuery* inside_query = nullptr;
  /// Touching bodies, when set: such a tet's centroid must moreover lie in its own region's body
  /// (the mesh check's "no tet across an interface"); replace() and inside_ok_moved() test it.
  const RegionQuery* region_query = nullptr;
  /// True when tet ids (positions p), of region r, has no surface vertex or its centroid lies
  /// in body r (always true without region_query).
  bool region_ok(const std::uint32_t* ids, const double* const* p, std::uint32_t r) const {
    if (!region_query) return true;
    if (!has_surface_vertex(ids)) return true;
    double c[3];
    centroid(p, c);
    return region_query->in_body(c, r);
  }
  /// False when ids (with positions p) form such a tet with its centroid not strictly inside;
  /// true otherwise (and always when inside_query is not set).
  bool inside_ok(const std::uint32_t* ids, const double* const* p) const {
    if (!inside_query) return true;
    if (!has_surface_vertex(ids)) return true;
    double c[3];
    centroid(p, c);
    return inside_query->side(c) > 0;
  }
  /// inside_ok for a tet that replaces the tets `old`: a centroid joined by a segment meeting
  /// no facet (exact) to the known-inside centroid of one of them is inside with no ray
  /// parity query (the first known one is tried), else the query decides.
  bool inside_ok_replacing(const std::uint32_t* ids, const double* const* p,
                           const std::vector<std::uint32_t>& old) const {
    if (!inside_query) return true;
    if (!has_surface_vertex(ids)) return true;
    double c[3];
    centroid(p, c);
    for (const std::uint32_t t : old) {
      if (!inside_known_[t]) continue;
      const std::uint32_t* o = v(t);
      const double* q[4] = {this->p(o[0]), this->p(o[1]), this->p(o[2]), this->p(o[3])};
      double c0[3];
      centroid(q, c0);
      if (inside_query->segment_clear(c0, c)) return true;
      break;
    }
    return inside_query->side(c) > 0;
  }
  /// Some vertex of tet ids is not interior-kind: the tets inside_ok, inside_ok_moved and
  /// region_ok test.
  bool has_surface_vertex(const std::uint32_t* ids) const {
    for (int k = 0; k < 4; ++k)
      if (nodes_->kind[ids[k]] != NodeKind::interior) return true;
    return false;
  }
  /// The centroid as inside_ok computes it (one formula, so a marked centroid is recomputed
  /// bit for bit).
  static void centroid(const double* const* p, double* c) {
    for (int i = 0; i < 3; ++i) c[i] = (p[0][i] + p[1][i] + p[2][i] + p[3][i]) / 4;
  }

  /// inside_ok for tet t with its vertex in slot iv moved to x. When t's current centroid is
  /// known to be strictly inside (mark_inside), a move whose centroid path meets no facet
  /// (SurfaceQuery::segment_clear: facet boxes first, then exact segment-facet tests) is
  /// accepted without the ray-parity query (exact: the side cannot change along a segment
  /// that does not meet the surface).
  bool inside_ok_moved(std::uint32_t t, int iv, const double* x) const {
    if (!inside_query) return true;
    const std::uint32_t* ids = v(t);
    const double* p[4] = {this->p(ids[0]), this->p(ids[1]), this->p(ids[2]), this->p(ids[3])};
    if (!has_surface_vertex(ids)) return true;
    double c0[3], c1[3];
    centroid(p, c0);
    p[iv] = x;
    centroid(p, c1);
    if (region_query) {  // the region's body holds the union's points: one test for both
      if (inside_known_[t] && inside_query->segment_clear(c0, c1) && region_query->interfaces().segment_clear(c0, c1))
        return true;
      return region_query->in_body(c1, region_[t]);
    }
    if (inside_known_[t] && inside_query->segment_clear(c0, c1)) return true;
    return inside_query->side(c1) > 0;
  }
  /// Tet t's centroid (at the current positions) passed inside_ok or inside_ok_moved. Threads
  /// may mark different tets at once.
  void mark_inside(std::uint32_t t) { inside_known_[t] = 1; }
  /// Marks inside, once inside_query (and region_query, if any) is set, every tet with a
  /// surface vertex whose centroid lies strictly inside (with regions: in its region's body):
  /// centroid_sides over those tets and the faces between them, one exact inside test per
  /// connected set instead of one at each tet's first move.
  void certify_inside();

  /// Writes the tets back (compacted, in slot order), the regions, and the boundary faces:
  /// the faces of mesh.boundary that are still boundary faces keep their order and vertex
  /// order, new ones follow (oriented outward); boundary_tet is recomputed. Nodes no tet uses
  /// are removed (ids compacted). Returns the number of boundary faces that changed.
  std::size_t write_back(VolumeMesh& mesh) const;

 private:
  /// The constructor's two halves: ta_ from matching the tets' faces (CheckError if a face is
  /// in more than two), and locked_ for the nodes of faces between regions.
  void match_faces(std::size_t np);
  void lock_interfaces(std::size_t np);
  void link_face(std::uint32_t t, int i, std::uint32_t ref);
  /// One step around an edge: from tet cur, holding the edge and the vertices c and d, over
  /// its face opposite c. False at the boundary; else cur is the next tet and (c, d) become
  /// (d, its vertex across).
  bool turn(std::uint32_t& cur, std::uint32_t& c, std::uint32_t& d) const;
  /// Clears ring and tets, and finds tet t's two vertices other than a and b in the order
  /// (c, d) for which (a, b, c, d) is positive. False if a or b is not in t.
  bool ring_start(std::uint32_t t, std::uint32_t a, std::uint32_t b, std::vector<std::uint32_t>& ring,
                  std::vector<std::uint32_t>& tets, std::uint32_t& c, std::uint32_t& d) const;
  /// A slot from `from` (a free list), or a new one at the end.
  std::uint32_t new_slot(std::vector<std::uint32_t>& from);

  // Per-slot arrays are allocated without zeroing and filled on all threads (the
  // constructor): zeroed by the allocating thread, their pages cost the paper gear box's main
  // thread 0.7 s with the second core idle.
  template <class T>
  using SlotArray = std::vector<T, UninitAllocator<T>>;
  NodeSet* nodes_;
  SlotArray<std::uint32_t> tv_, ta_, region_, version_;
  std::vector<std::uint32_t> vtet_, free_;
  std::vector<std::uint8_t> locked_;  // per vertex: on an interface
  SlotArray<std::uint8_t> inside_known_;  // per slot: centroid certified strictly inside
};

/// Position of vertex x in the 4 ids at v (0..3), or -1.
inline int index_in(const std::uint32_t* v, std::uint32_t x) {
  for (int i = 0; i < 4; ++i)
    if (v[i] == x) return i;
  return -1;
}

}  // namespace kdmesh
