// kdmesh — exterior and interface groups of named bodies (mesher/fe/body_groups.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/fe/body_groups.h"

#include <algorithm>
#include <array>
#include <map>
#include <utility>

#include "core/error.h"

namespace kdmesh {

BodyGroupStats add_body_groups(FeMesh& fe, const VolumeMesh& mesh, std::uint32_t num_patches,
                               const std::vector<std::string>& names) {
  BodyGroupStats st;
  const std::size_t nt = mesh.num_tets(), nb = mesh.boundary.size() / 3;
  if (fe.order != 1 || fe.num_tets() != nt || fe.face_entity.size() != nb || mesh.boundary_tet.size() != nb ||
      mesh.tet_region.size() != nt)
    throw UsageError("add_body_groups: the FeMesh is not make_fe_mesh's of this mesh");
  for (std::uint32_t r : mesh.tet_region)
    if (r >= names.size())
      throw UsageError("add_body_groups: region " + std::to_string(r) + " has no name (" +
                       std::to_string(names.size()) + " names)");
  auto add = [&](FeGroup g) {
    for (const FeGroup& o : fe.groups)
      if (o.dim == g.dim && o.name == g.name)
        throw UsageError("the group '" + g.name + "' of the bodies is already a dim 2 group's name");
    fe.groups.push_back(std::move(g));
  };
  // Exteriors.
  std::vector<std::vector<std::uint32_t>> exterior(names.size());
  for (std::size_t f = 0; f < nb; ++f) exterior[mesh.tet_region[mesh.boundary_tet[f]]].push_back(fe.face_entity[f]);
  for (std::size_t b = 0; b < names.size(); ++b) {
    std::vector<std::uint32_t>& e = exterior[b];
    std::sort(e.begin(), e.end());
    e.erase(std::unique(e.begin(), e.end()), e.end());
    if (!e.empty()) add({names[b] + "-exterior", 2, std::move(e)});
  }
  // Interfaces: faces of two tets of different regions, found by matching the tets' faces.
  static constexpr int kF[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  struct Face {
    std::array<std::uint32_t, 3> key, out;
    std::uint32_t region;
  };
  std::vector<Face> faces;
  for (std::size_t t = 0; t < nt; ++t)
    for (int i = 0; i < 4; ++i) {
      Face f;
      for (int j = 0; j < 3; ++j) f.out[std::size_t(j)] = mesh.tets[4 * t + std::size_t(kF[i][j])];
      f.key = f.out;
      std::sort(f.key.begin(), f.key.end());
      f.region = mesh.tet_region[t];
      faces.push_back(f);
    }
  std::sort(faces.begin(), faces.end(), [](const Face& a, const Face& b) {
    return a.key != b.key ? a.key < b.key : a.region < b.region;
  });
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::array<std::uint32_t, 3>>> pairs;
  for (std::size_t i = 0; i + 1 < faces.size(); ++i)
    if (faces[i].key == faces[i + 1].key && faces[i].region != faces[i + 1].region)
      pairs[{faces[i].region, faces[i + 1].region}].push_back(faces[i].out);  // out of the lower region
  std::uint32_t entity = num_patches;
  for (const auto& [ab, list] : pairs) {
    for (const auto& f : list) {
      fe.faces.insert(fe.faces.end(), f.begin(), f.end());
      fe.face_entity.push_back(entity);
    }
    add({names[ab.first] + "-" + names[ab.second], 2, {entity}});
    st.interface_faces += list.size();
    ++st.interfaces;
    ++entity;
  }
  return st;
}

}  // namespace kdmesh
