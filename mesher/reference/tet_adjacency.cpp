// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/reference/tet_adjacency.h"

#include <algorithm>
#include <array>
#include <string>

#include "core/error.h"

namespace kdmesh {

namespace {

constexpr std::uint32_t kNone = 0xFFFFFFFFu;

struct FaceRef {
  std::array<std::uint32_t, 3> key;  // sorted vertex ids
  std::uint32_t face;                // 4*t + i
};

void link_all_faces(Triangulation& tri) {
  const std::size_t m = tri.num_tets();
  std::vector<FaceRef> faces;
  faces.reserve(4 * m);
  for (std::size_t t = 0; t < m; ++t)
    for (int f = 0; f < 4; ++f) {
      FaceRef r{};
      for (int i = 0, k = 0; i < 4; ++i)
        if (i != f) r.key[k++] = tri.v(t, i);
      std::sort(r.key.begin(), r.key.end());
      r.face = std::uint32_t(4 * t + f);
      faces.push_back(r);
    }
  std::sort(faces.begin(), faces.end(), [](const FaceRef& a, const FaceRef& b) {
    return a.key != b.key ? a.key < b.key : a.face < b.face;
  });
  
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j - i > 2)
      throw CheckError("face (" + std::to_string(faces[i].key[0]) + " " +
                       std::to_string(faces[i].key[1]) + " " + std::to_string(faces[i].key[2]) +
                       ") is shared by " + std::to_string(j - i) + " tets");
    if (j - i == 2) {
      tri.adj(faces[i].face >> 2, faces[i].face & 3) = faces[i + 1].face;
      tri.adj(faces[i + 1].face >> 2, faces[i + 1].face & 3) = faces[i].face;
    }
    i = j;
  }
}

}  // namespace

Triangulation triangulation_from_tets(const std::vector<std::uint32_t>& tets) {
  Triangulation tri;
  tri.data.assign(2 * tets.size(), kNone);
  for (std::size_t t = 0; t < tets.size() / 4; ++t)
    for (int i = 0; i < 4; ++i) tri.v(t, i) = tets[4 * t + i];
  link_all_faces(tri);
  // Close every hull face with an infinite tet, oriented like the kernel's: the finite tet
  // with the hull face's opposite vertex replaced by the infinite one, two others swapped.
  const std::size_t m = tri.num_tets();
  for (std::size_t t = 0; t < m; ++t)
    for (int f = 0; f < 4; ++f)
      if (tri.adj(t, f) == kNone) {
        std::array<std::uint32_t, 8> rec;
        rec.fill(kNone);
        for (int i = 0; i < 4; ++i) rec[i] = tri.v(t, i);
        rec[f] = kInfiniteVertex;
        std::swap(rec[(f + 1) % 4], rec[(f + 2) % 4]);
        tri.data.insert(tri.data.end(), rec.begin(), rec.end());
      }
  link_all_faces(tri);
  for (std::size_t t = 0; t < tri.num_tets(); ++t)
    for (int f = 0; f < 4; ++f)
      if (tri.adj(t, f) == kNone)
        throw CheckError("tet " + std::to_string(t) + " face " + std::to_string(f) +
                       " has no neighbour: the tets do not form a closed triangulation");
  return tri;
}

}  // namespace kdmesh
