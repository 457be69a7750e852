// kdmesh — finite-element meshes from the volume mesh (C3D4, and C3D10 with curved boundary).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/fe/fe_assembly.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/timer.h"

namespace kdmesh {

namespace {

/// Corner pairs of the six mid-edge nodes, in core/fe_mesh.h (VTK / Abaqus C3D10) order.
constexpr int kTetEdge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
constexpr int kFaceEdge[3][2] = {{0, 1}, {1, 2}, {2, 0}};

/// mid[i][j]: the local index (4..9) of the mid-edge node between corners i and j.
constexpr int kMid[4][4] = {{-1, 4, 6, 7}, {4, -1, 5, 8}, {6, 5, -1, 9}, {7, 8, 9, -1}};

}  // namespace

// Shape functions of the 10-node tet in barycentric coordinates L0..L3 (L0 = 1 - xi - eta -
// zeta, L1 = xi, L2 = eta, L3 = zeta):
//   corners      N_i  = L_i (2 L_i - 1)
//   mid-edge ij  N_ij = 4 L_i L_j
// x(L) = sum N_k x_k. Taking the L_i as independent,
//   G_i = dx/dL_i = (4 L_i - 1) x_i + sum_{j != i} 4 L_j x_ij,
// and since dL_0/dxi_j = -1, dL_j/dxi_j = 1, the Jacobian's columns are dx/dxi_j = G_j - G_0
// (j = 1..3); det J = (G_1 - G_0) . ((G_2 - G_0) x (G_3 - G_0)).
// Check: with x_ij = (x_i + x_j) / 2, G_i = x_i + 2 sum_j L_j x_j, so G_j - G_0 = x_j - x_0 and
// det J = 6 V everywhere (the straight tet).
double quadratic_tet_jacobian(const double* const x[10], const double L[4]) {
  double G[4][3];
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) {
      double g = (4 * L[i] - 1) * x[i][k];
      for (int j = 0; j < 4; ++j)
        if (j != i) g += 4 * L[j] * x[kMid[i][j]][k];
      G[i][k] = g;
    }
  double a[3], b[3], c[3];
  for (int k = 0; k < 3; ++k) a[k] = G[1][k] - G[0][k], b[k] = G[2][k] - G[0][k], c[k] = G[3][k] - G[0][k];
  return a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) +
         a[2] * (b[0] * c[1] - b[1] * c[0]);
}

double quadratic_tet_min_jacobian_ratio(const double* const x[10]) {
  double a[3], b[3], c[3];
  for (int k = 0; k < 3; ++k) a[k] = x[1][k] - x[0][k], b[k] = x[2][k] - x[0][k], c[k] = x[3][k] - x[0][k];
  const double six_v = a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) +
                       a[2] * (b[0] * c[1] - b[1] * c[0]);
  if (!(six_v > 0)) return -std::numeric_limits<double>::infinity();
  // The 4 corners, then the 4-point Gauss rule (degree 2): L = (ga, gb, gb, gb) and
  // permutations, ga = (5 + 3 sqrt 5) / 20, gb = (5 - sqrt 5) / 20.
  const double ga = 0.58541019662496845446, gb = 0.13819660112501051518;
  double r = std::numeric_limits<double>::infinity();
  for (int s = 0; s < 8; ++s) {
    double L[4];
    for (int i = 0; i < 4; ++i) L[i] = s < 4 ? (i == s ? 1.0 : 0.0) : (i == s - 4 ? ga : gb);
    r = std::min(r, quadratic_tet_jacobian(x, L) / six_v);
  }
  return r;
}

double quadratic_tet_volume(const double* const x[10]) {
  const double centre[4] = {0.25, 0.25, 0.25, 0.25};
  double v = -0.8 * quadratic_tet_jacobian(x, centre);
  for (int s = 0; s < 4; ++s) {
    double L[4];
    for (int i = 0; i < 4; ++i) L[i] = i == s ? 0.5 : 1.0 / 6;
    v += 0.45 * quadratic_tet_jacobian(x, L);
  }
  return v / 6;  // the reference tet has volume 1/6
}

double fe_mesh_volume(const FeMesh& fe) {
  double v = 0;
  const int n = fe.tet_nodes();
  for (std::size_t t = 0; t < fe.num_tets(); ++t) {
    const std::uint32_t* e = &fe.tets[std::size_t(n) * t];
    const double* x[10];
    for (int i = 0; i < 4; ++i) x[i] = fe.points.p(e[i]);
    if (n == 10) {
      for (int i = 4; i < 10; ++i) x[i] = fe.points.p(e[i]);
      v += quadratic_tet_volume(x);
    } else {
      double a[3], b[3], c[3];
      for (int k = 0; k < 3; ++k) a[k] = x[1][k] - x[0][k], b[k] = x[2][k] - x[0][k], c[k] = x[3][k] - x[0][k];
      v += (a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) +
            a[2] * (b[0] * c[1] - b[1] * c[0])) / 6;
    }
  }
  return v;
}

FeMesh make_fe_mesh(const VolumeMesh& mesh, const BoundaryGroups& bg, std::vector<FeGroup> groups) {
  const std::size_t nb = mesh.boundary.size() / 3;
  if (bg.face_patch.size() != nb || bg.edge_curve.size() * 2 != bg.edges.size())
    throw UsageError("make_fe_mesh: the boundary groups are of another mesh (" +
                     std::to_string(bg.face_patch.size()) + " face patches for " + std::to_string(nb) +
                     " boundary faces)");
  for (std::size_t f = 0; f < nb; ++f)
    if (bg.face_patch[f] == kNoEntity)
      throw UsageError("make_fe_mesh: boundary face " + std::to_string(f) + " has no patch");
  if (mesh.tet_region.size() != mesh.num_tets())
    throw UsageError("make_fe_mesh: the mesh has " + std::to_string(mesh.tet_region.size()) +
                     " tet regions for " + std::to_string(mesh.num_tets()) + " tets");
  FeMesh fe;
  fe.points = mesh.nodes.points;
  fe.order = 1;
  fe.tets = mesh.tets;
  fe.tet_entity = mesh.tet_region;
  fe.faces = mesh.boundary;
  fe.face_entity = bg.face_patch;
  fe.edges = bg.edges;
  fe.edge_entity = bg.edge_curve;
  fe.groups = std::move(groups);
  return fe;
}

namespace {

/// The mesh's edges, numbered by (smaller id, larger id): per smaller node its larger
/// neighbours, sorted (CSR). Edge k joins a[k] and b[k].
struct MeshEdges {
  std::size_t n0 = 0;  ///< corner nodes
  std::vector<std::uint32_t> start, a, b;

  std::size_t size() const { return a.size(); }
  /// The edge joining corner nodes u and v; size() when they share none.
  std::size_t index(std::uint32_t u, std::uint32_t v) const {
    if (u > v) std::swap(u, v);
    if (v >= n0) return size();
    const auto lo = b.begin() + start[u], hi = b.begin() + start[u + 1];
    const auto it = std::lower_bound(lo, hi, v);
    return it != hi && *it == v ? std::size_t(it - b.begin()) : size();
  }
};

/// Numbers the edges of the tets, and writes each tet's mid-edge node ids (n0 + edge) into
/// slots 4..9 of its 10 in tets10. Each smaller node's neighbours come with the tet slot
/// (6 t + local edge) they came from, sorted: cheaper than one sort of all 6 T edges.
MeshEdges number_edges(const FeMesh& fe, std::vector<std::uint32_t>& tets10) {
  const std::size_t ntet = fe.num_tets(), n0 = fe.points.size();
  MeshEdges E;
  E.n0 = n0;
  E.start.assign(n0 + 1, 0);
  tets10.assign(10 * ntet, 0);
  for (std::size_t t = 0; t < ntet; ++t)
    for (const auto& e : kTetEdge) {
      const std::uint32_t a = fe.tets[4 * t + e[0]], b = fe.tets[4 * t + e[1]];
      if (a >= n0 || b >= n0 || a == b)
        throw UsageError("make_quadratic: tet " + std::to_string(t) + " has a bad node id");
      ++E.start[std::min(a, b) + 1];
    }
  for (std::size_t v = 0; v < n0; ++v) E.start[v + 1] += E.start[v];
  std::vector<std::uint64_t> slots(6 * ntet);  // larger node << 32 | slot
  std::vector<std::uint32_t> fill(E.start.begin(), E.start.end() - 1);
  for (std::size_t t = 0; t < ntet; ++t)
    for (int e = 0; e < 6; ++e) {
      const std::uint32_t a = fe.tets[4 * t + kTetEdge[e][0]], b = fe.tets[4 * t + kTetEdge[e][1]];
      slots[fill[std::min(a, b)]++] = (std::uint64_t(std::max(a, b)) << 32) | std::uint32_t(6 * t + e);
    }
  for (std::size_t v = 0; v < n0; ++v) {
    const auto b = slots.begin() + E.start[v], e = slots.begin() + E.start[v + 1];
    std::sort(b, e);
    E.start[v] = std::uint32_t(E.a.size());
    for (auto it = b; it != e; ++it) {
      const std::uint32_t nb = std::uint32_t(*it >> 32), slot = std::uint32_t(*it);
      if (it == b || nb != E.b.back()) E.a.push_back(std::uint32_t(v)), E.b.push_back(nb);
      tets10[10 * (slot / 6) + 4 + slot % 6] = std::uint32_t(n0 + E.a.size() - 1);
    }
  }
  E.start[n0] = std::uint32_t(E.a.size());
  if (n0 + E.size() > kNoEntity)
    throw UsageError("make_quadratic: " + std::to_string(n0 + E.size()) + " nodes exceed 32-bit ids");
  return E;
}

constexpr std::uint32_t kMixed = kNoEntity - 1;  // an edge between two patches

/// What each edge lies on: a curve (edge_curve), a patch (edge_patch; kMixed between two),
/// or nothing (interior).
void edge_entities(const FeMesh& fe, const MeshEdges& E, const SurfacePatches& patches,
                   std::vector<std::uint32_t>& edge_curve, std::vector<std::uint32_t>& edge_patch) {
  edge_curve.assign(E.size(), kNoEntity);
  edge_patch.assign(E.size(), kNoEntity);
  for (std::size_t f = 0; f < fe.num_faces(); ++f)
    for (const auto& e : kFaceEdge) {
      const std::size_t k = E.index(fe.faces[3 * f + e[0]], fe.faces[3 * f + e[1]]);
      if (k == E.size())
        throw UsageError("make_quadratic: boundary face " + std::to_string(f) + " has an edge of no tet");
      if (fe.face_entity[f] >= patches.num_patches) continue;  // between two bodies: inside the solid
      std::uint32_t& p = edge_patch[k];
      p = p == kNoEntity || p == fe.face_entity[f] ? fe.face_entity[f] : kMixed;
    }
  for (std::size_t s = 0; s < fe.num_edges(); ++s) {
    const std::size_t k = E.index(fe.edges[2 * s], fe.edges[2 * s + 1]);
    if (k == E.size())
      throw UsageError("make_quadratic: feature edge " + std::to_string(s) + " is an edge of no tet");
    edge_curve[k] = fe.edge_entity[s];
  }
}

/// The mid-edge nodes: each at midpoint + scale * (target - midpoint), target its point on
/// the surface (scale 0: straight).
struct MidNodes {
  const FeMesh& fe;
  const MeshEdges& E;
  std::vector<double> mid, target;
  std::vector<float> scale;

  MidNodes(const FeMesh& f, const MeshEdges& e)
      : fe(f), E(e), mid(3 * e.size()), target(3 * e.size()), scale(e.size(), 0.0f) {}
  void midpoint(std::size_t k, double* out) const {
    const double* a = fe.points.p(E.a[k]);
    const double* b = fe.points.p(E.b[k]);
    for (int q = 0; q < 3; ++q) out[q] = (a[q] + b[q]) / 2;
  }
  void place(std::size_t k) {
    midpoint(k, &mid[3 * k]);
    if (scale[k] > 0)
      for (int q = 0; q < 3; ++q) mid[3 * k + q] += double(scale[k]) * (target[3 * k + q] - mid[3 * k + q]);
  }
  const double* pos(std::uint32_t id) const { return id < E.n0 ? fe.points.p(id) : &mid[3 * (id - E.n0)]; }
};

/// Boundary mid-nodes moved onto their curve or curved patch (options.curved), unless that
/// moves one farther than options.max_move x its edge.
void project_mid_nodes(MidNodes& M, const std::vector<std::uint32_t>& edge_curve,
                       const std::vector<std::uint32_t>& edge_patch, const SurfaceMesh& surface,
                       const SurfaceQuery& query, const SurfacePatches& patches, const QuadraticOptions& options,
                       QuadraticStats& st) {
  PatchQuery pq(surface, patches);
  for (std::size_t k = 0; k < M.E.size(); ++k) {
    double* m = &M.mid[3 * k];
    M.midpoint(k, m);
    const bool on_curve = edge_curve[k] != kNoEntity;
    const bool on_patch = !on_curve && edge_patch[k] != kNoEntity && edge_patch[k] != kMixed;
    st.curve_mid_nodes += on_curve;
    st.patch_mid_nodes += on_patch;
    // A mid-node of an edge in a planar patch is on the patch already (its two faces are).
    if (!options.curved || !(on_curve || on_patch) || (on_patch && patches.patch_planar[edge_patch[k]]))
      continue;
    double p[3];
    if (on_curve) {
      pq.closest_on_curve(m, edge_curve[k], p);
    } else {
      std::uint32_t f = kNoFacet;
      query.closest(m, p, &f);
      if (f >= patches.facet_patch.size() || patches.facet_patch[f] != edge_patch[k])
        pq.closest_in_patch(m, edge_patch[k], p);
    }
    const double* a = M.fe.points.p(M.E.a[k]);
    const double* b = M.fe.points.p(M.E.b[k]);
    const double len = std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    const double move = std::hypot(p[0] - m[0], p[1] - m[1], p[2] - m[2]);
    if (move > options.max_move * len) {
      ++st.far_projections;
      continue;
    }
    if (move > 0) {
      ++st.moved_mid_nodes;
      st.max_move = std::max(st.max_move, move / len);
      std::copy(p, p + 3, &M.target[3 * k]);
      std::copy(p, p + 3, m);
      M.scale[k] = 1;
    }
  }
}

/// Validity: a failing element has the curvature of its curved edges halved (options.
/// halving_steps times), then removed (straight midpoints), until every element passes.
/// Scales only decrease, and an all-straight element has det J = 6 V: this terminates. Only
/// elements with a curved edge need the test; the others need 6 V > 0.
void make_elements_valid(MidNodes& M, const std::vector<std::uint32_t>& tets10, const QuadraticOptions& options,
                         QuadraticStats& st) {
  const std::size_t ntet = tets10.size() / 10, n0 = M.E.n0;
  auto ratio = [&](std::size_t t) {
    const double* x[10];
    for (int i = 0; i < 10; ++i) x[i] = M.pos(tets10[10 * t + i]);
    return quadratic_tet_min_jacobian_ratio(x);
  };
  std::vector<std::uint32_t> check;
  for (std::size_t t = 0; t < ntet; ++t) {
    bool any = false;
    for (int e = 0; e < 6; ++e) any |= M.scale[tets10[10 * t + 4 + e] - n0] > 0;
    if (any) {
      check.push_back(std::uint32_t(t));
      continue;
    }
    const double *x0 = M.pos(tets10[10 * t]), *x1 = M.pos(tets10[10 * t + 1]), *x2 = M.pos(tets10[10 * t + 2]),
                 *x3 = M.pos(tets10[10 * t + 3]);
    double a[3], b[3], c[3];
    for (int k = 0; k < 3; ++k) a[k] = x1[k] - x0[k], b[k] = x2[k] - x0[k], c[k] = x3[k] - x0[k];
    st.invalid_linear += !(a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) +
                               a[2] * (b[0] * c[1] - b[1] * c[0]) > 0);
  }
  const float smallest = std::ldexp(1.0f, -std::clamp(options.halving_steps, 0, 20));
  std::vector<char> invalid_linear(ntet, 0), reduced(ntet, 0);
  for (bool changed = true; changed;) {
    changed = false;
    for (std::uint32_t t : check) {
      if (invalid_linear[t]) continue;
      const double r = ratio(t);
      if (r > 0 && r >= options.min_jacobian_ratio) continue;
      bool any = false;
      for (int e = 0; e < 6; ++e) {
        const std::size_t k = tets10[10 * t + 4 + e] - n0;
        if (M.scale[k] == 0) continue;
        M.scale[k] = M.scale[k] > smallest ? M.scale[k] / 2 : 0.0f;
        if (M.scale[k] == 0) ++st.straightened_edges;
        M.place(k);
        any = true;
      }
      if (any) {
        st.reduced_elements += !reduced[t];
        reduced[t] = 1;
        changed = true;
      } else {
        invalid_linear[t] = 1;
        ++st.invalid_linear;
      }
    }
  }
  for (std::uint32_t t : check) {
    if (!reduced[t]) continue;
    bool straight = true;
    for (int e = 0; e < 6; ++e) straight &= M.scale[tets10[10 * t + 4 + e] - n0] == 0;
    st.straightened_elements += straight;
  }
  for (std::size_t k = 0; k < M.E.size(); ++k) st.reduced_edges += M.scale[k] > 0 && M.scale[k] < 1;
  // The figure reported: over the elements checked (the others have det J = 6 V exactly, a
  // ratio of 1 up to rounding).
  st.min_jacobian_ratio = ntet > 0 ? 1.0 : 0.0;
  for (std::uint32_t t : check) st.min_jacobian_ratio = std::min(st.min_jacobian_ratio, ratio(t));
}

}  // namespace

QuadraticStats make_quadratic(FeMesh& fe, const SurfaceMesh& surface, const SurfaceQuery& query,
                              const SurfacePatches& patches, const QuadraticOptions& options) {
  Stopwatch clock;
  QuadraticStats st;
  if (fe.order != 1) throw UsageError("make_quadratic: the mesh is already of order " + std::to_string(fe.order));
  if (fe.tets.size() % 4 || fe.faces.size() % 3 || fe.edges.size() % 2 ||
      fe.face_entity.size() != fe.num_faces() || fe.edge_entity.size() != fe.num_edges())
    throw UsageError("make_quadratic: inconsistent FeMesh arrays");
  for (std::uint32_t c : fe.edge_entity)
    if (c >= patches.num_curves())
      throw UsageError("make_quadratic: edge curve " + std::to_string(c) + " is not a curve of the surface (" +
                       std::to_string(patches.num_curves()) + " curves)");
  const std::size_t ntet = fe.num_tets(), n0 = fe.points.size();
  std::vector<std::uint32_t> tets10;
  const MeshEdges E = number_edges(fe, tets10);
  st.mid_nodes = E.size();
  std::vector<std::uint32_t> edge_curve, edge_patch;
  edge_entities(fe, E, patches, edge_curve, edge_patch);
  MidNodes M(fe, E);
  project_mid_nodes(M, edge_curve, edge_patch, surface, query, patches, options, st);
  // Element connectivity: the corners (the mid-edge ids are in already).
  for (std::size_t t = 0; t < ntet; ++t) std::copy(&fe.tets[4 * t], &fe.tets[4 * t] + 4, &tets10[10 * t]);
  make_elements_valid(M, tets10, options, st);

  // Faces and edges of order 2.
  std::vector<std::uint32_t> faces6(6 * fe.num_faces());
  for (std::size_t f = 0; f < fe.num_faces(); ++f) {
    const std::uint32_t* c = &fe.faces[3 * f];
    std::copy(c, c + 3, &faces6[6 * f]);
    for (int e = 0; e < 3; ++e)
      faces6[6 * f + 3 + e] = std::uint32_t(n0 + E.index(c[kFaceEdge[e][0]], c[kFaceEdge[e][1]]));
  }
  std::vector<std::uint32_t> edges3(3 * fe.num_edges());
  for (std::size_t s = 0; s < fe.num_edges(); ++s) {
    edges3[3 * s] = fe.edges[2 * s], edges3[3 * s + 1] = fe.edges[2 * s + 1];
    edges3[3 * s + 2] = std::uint32_t(n0 + E.index(fe.edges[2 * s], fe.edges[2 * s + 1]));
  }
  fe.points.xyz.insert(fe.points.xyz.end(), M.mid.begin(), M.mid.end());
  fe.tets = std::move(tets10);
  fe.faces = std::move(faces6);
  fe.edges = std::move(edges3);
  fe.order = 2;
  st.seconds = clock.seconds();
  return st;
}

}  // namespace kdmesh
