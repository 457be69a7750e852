// kdmesh — welding of surface points with bit-identical coordinates (see point_welder.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "io/point_welder.h"

namespace kdmesh {

void PointWelder::grow() {
  std::vector<std::uint32_t> old(slots_.size() * 2, kEmpty);
  old.swap(slots_);
  const std::size_t mask = slots_.size() - 1;
  for (std::uint32_t id : old) {
    if (id == kEmpty) continue;
    const double* p = out_.p(id);
    const std::uint64_t k[3] = {bits(p[0]), bits(p[1]), bits(p[2])};
    std::size_t i = hash(k) & mask;
    while (slots_[i] != kEmpty) i = (i + 1) & mask;
    slots_[i] = id;
  }
}

void weld_file_vertices(const std::vector<double>& raw, SurfaceMesh& mesh) {
  const std::size_t nv = raw.size() / 3;
  std::vector<std::uint32_t> remap(nv);
  PointWelder weld(mesh.points, nv);
  for (std::size_t i = 0; i < nv; ++i) remap[i] = weld.add(raw[3 * i], raw[3 * i + 1], raw[3 * i + 2]);
  for (std::uint32_t& v : mesh.tris) v = remap[v];
}

}  // namespace kdmesh
