// kdmesh — a 1e6-triangle "scan" through the whole pipeline (issue 6): a finely tessellated
// torus with seeded radial roughness, as a 3D scanner exports it, written as binary STL,
// meshed end to end, and checked.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "io/surface_io.h"
#include "tests/support/scratch.h"
#include "tests/support/torus.h"
#include "tools/app/mesh_job.h"

namespace kdmesh {
namespace {

TEST(LargeScan, MillionTriangleTorusMeshesEndToEnd) {
  const double R = 40, r = 10;
  const int nu = 1000, nv = 500;  // 1,000,000 triangles
  const SurfaceMesh scan = test::rough_torus(R, r, nu, nv, 0.05, 7);  // roughness 5% of the step
  ASSERT_EQ(scan.num_tris(), 1000000u);
  const std::string stl = test::scratch_path("large_scan", ".stl");
  write_stl(scan, stl);

  MeshJob job;
  job.name = "scan";
  job.input = stl;
  job.sizing.max_size = 2.5;  // coarse against the facets: the surface is resampled
  job.sharp_angle = 60;       // the roughness is no feature
  const MeshJobResult res = run_mesh_job(job);
  ASSERT_TRUE(res.ok()) << res.summary.dump(1);
  const nlohmann::json& s = res.summary;
  EXPECT_EQ(s["counts"]["surface_facets"], 1000000);
  EXPECT_EQ(s["counts"]["bodies"], 1);
  EXPECT_EQ(s["counts"]["feature_edges"], 0);
  EXPECT_TRUE(s["mesh_check"]["pass"].get<bool>()) << s["mesh_check"].dump(1);
  // The solid's volume is 2 pi^2 R r^2 up to the tessellation and the roughness; the mesh
  // check holds the mesh to the STL's own volume (0.5%).
  const double torus = 2 * std::numbers::pi * std::numbers::pi * R * r * r;
  EXPECT_NEAR(s["solid_volume"].get<double>(), torus, 0.01 * torus);
  EXPECT_GT(s["counts"]["tets"].get<std::size_t>(), 10000u);
  // The estimate saw the same surface.
  EXPECT_GT(s["estimate"]["nodes"].get<double>(), 0.5 * s["counts"]["placed_nodes"].get<double>());
  EXPECT_LT(s["estimate"]["nodes"].get<double>(), 2.0 * s["counts"]["placed_nodes"].get<double>());
  if (res.ok()) std::remove(stl.c_str());
}

}  // namespace
}  // namespace kdmesh
