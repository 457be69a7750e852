// kdmesh consumer: meshes the unit cube through the installed library's front door and checks
// the result, so that the install_consumer test proves headers, libraries and their
// dependencies are all found from the installed tree. With a path argument it also writes the
// mesh as VTU through kdmesh::io (whose VTK dependency then has to link too).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>

#include <kdmesh/io/vtu_writer.h>
#include <kdmesh/mesher/mesh_solid.h>  // the prefixed spelling; "mesher/mesh_solid.h" works too

int main(int argc, char** argv) {
  // The unit cube: 8 corners, 12 triangles with outward normals.
  kdmesh::SurfaceMesh cube;
  for (int i = 0; i < 8; ++i) cube.points.push_back(i & 1, i >> 1 & 1, i >> 2 & 1);
  for (std::uint32_t v : {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                          2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5})
    cube.tris.push_back(v);

  kdmesh::MeshParams params;
  params.name = "cube";
  params.sizing.max_size = 0.3;
  params.sizing.min_size = 0.3 / 1000;
  try {
    const kdmesh::MeshResult r = kdmesh::mesh_solid(cube, params);
    const kdmesh::VolumeMesh& m = r.mesh;
    double volume = 0;
    for (std::size_t t = 0; t < m.num_tets(); ++t) {
      const double* p[4];
      for (int k = 0; k < 4; ++k) p[k] = m.nodes.points.p(m.tets[4 * t + k]);
      double a[3], b[3], c[3];
      for (int k = 0; k < 3; ++k) a[k] = p[1][k] - p[0][k], b[k] = p[2][k] - p[0][k], c[k] = p[3][k] - p[0][k];
      volume += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                 a[2] * (b[0] * c[1] - b[1] * c[0])) / 6;
    }
    const bool check = r.report.has_check && r.report.check.ok();
    std::printf("nodes %zu tets %zu volume %.12f check %s\n", m.nodes.size_count(), m.num_tets(),
                volume, check ? "passed" : "FAILED");
    if (argc > 1) kdmesh::write_vtu(r.tet_mesh, argv[1]);
    return check && std::abs(volume - 1) <= 1e-9 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "kdmesh::mesh_solid failed: %s\n", e.what());
    return 1;
  }
}
