// kdmesh — tests of the opt-in surface repairs (mesher/surface/surface_repair.h): each defect is
// refused without its repair, fixed with it (the repaired surface validates and encloses the
// same volume), and reported; unsafe cases are left for validation to refuse.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <filesystem>

#include "core/error.h"
#include "io/surface_io.h"
#include "mesher/surface/surface_prepare.h"
#include "mesher/surface/surface_repair.h"
#include "tests/support/scratch.h"
#include "tools/app/mesh_job.h"

namespace kdmesh {
namespace {

/// The cube [0, 1]^3: 12 outward facets; facet 2q and 2q+1 split quad q along a diagonal.
SurfaceMesh cube() {
  SurfaceMesh m;
  for (int i = 0; i < 8; ++i) m.points.push_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads)
    for (const int t : {q[0], q[1], q[2], q[0], q[2], q[3]}) m.tris.push_back(std::uint32_t(t));
  return m;
}

SurfaceError::Defect defect_of(const SurfaceMesh& m) {
  try {
    prepare_surface(m, "test");
  } catch (const SurfaceError& e) {
    return e.defect();
  }
  ADD_FAILURE() << "the surface validated";
  return SurfaceError::Defect::other;
}

/// Repairs with `o`, then validates: the result must bound the unit cube.
SurfaceRepairReport repair_and_check(const SurfaceMesh& m, const SurfaceRepairOptions& o, std::size_t facets) {
  SurfaceRepairReport r;
  const SurfaceMesh fixed = repair_surface(m, o, r);
  EXPECT_EQ(fixed.num_tris(), facets);
  EXPECT_EQ(fixed.points.xyz, m.points.xyz);  // no point moves
  const PreparedSurface p = prepare_surface(fixed, "test");
  EXPECT_DOUBLE_EQ(p.volume, 1.0);
  EXPECT_EQ(p.num_bodies, 1u);
  return r;
}

TEST(SurfaceRepair, FlippedFacetIsFlippedBack) {
  SurfaceMesh m = cube();
  std::swap(m.tris[3 * 5 + 1], m.tris[3 * 5 + 2]);
  EXPECT_EQ(defect_of(m), SurfaceError::Defect::orientation);
  SurfaceRepairOptions o;
  o.orientation = true;
  const SurfaceRepairReport r = repair_and_check(m, o, 12);
  EXPECT_EQ(r.flipped, 1u);
  ASSERT_EQ(r.notes.size(), 1u);
  EXPECT_NE(r.notes[0].find("flipped 1 facet(s)"), std::string::npos) << r.notes[0];
  EXPECT_NE(r.notes[0].find("facets 5"), std::string::npos) << r.notes[0];
}

TEST(SurfaceRepair, SameWayDuplicatesAreRemovedOppositeOnesAreNot) {
  SurfaceMesh m = cube();
  for (int k = 0; k < 3; ++k) m.tris.push_back(m.tris[3 * 7 + std::size_t((k + 1) % 3)]);  // facet 7, rotated
  EXPECT_EQ(defect_of(m), SurfaceError::Defect::duplicates);
  SurfaceRepairOptions o;
  o.duplicates = true;
  const SurfaceRepairReport r = repair_and_check(m, o, 12);
  EXPECT_EQ(r.removed_duplicates, 1u);
  EXPECT_NE(r.notes.at(0).find("facets 12"), std::string::npos) << r.notes[0];  // the later copy goes

  // A copy facing the other way is a two-sided sheet: not safe to remove, left for validation.
  SurfaceMesh two = cube();
  two.tris.insert(two.tris.end(), {two.tris[21], two.tris[23], two.tris[22]});
  SurfaceRepairReport r2;
  const SurfaceMesh same = repair_surface(two, o, r2);
  EXPECT_EQ(same.tris, two.tris);
  EXPECT_FALSE(r2.changed());
  // ... and the refusal does not hint at the duplicates repair, which cannot fix it (issue 19).
  EXPECT_EQ(defect_of(same), SurfaceError::Defect::other);
}

TEST(SurfaceRepair, CollapsedFacetIsRemoved) {
  SurfaceMesh m = cube();
  m.tris.insert(m.tris.begin() + 9, {4, 4, 2});  // becomes facet 3; its edges 4-2, 2-4 cancel
  EXPECT_EQ(defect_of(m), SurfaceError::Defect::degenerate);
  SurfaceRepairOptions o;
  o.degenerate = true;
  const SurfaceRepairReport r = repair_and_check(m, o, 12);
  EXPECT_EQ(r.removed_collapsed, 1u);
  EXPECT_NE(r.notes.at(0).find("facets 3"), std::string::npos) << r.notes[0];
}

// A T-junction closed by a zero-area "cap": the side face y = 0 is split at the midpoint m of
// edge 0-1, and the cap (0, 1, m) pairs the bottom's edge 1->0 with the side's 0->m, m->1.
// The repair removes the cap and splits the bottom facet (0, 3, 1) at m into (1, m, 3) and
// (m, 0, 3): the same region of the plane z = 0, oriented the same way.
TEST(SurfaceRepair, CollinearCapIsRemovedBySplittingItsNeighbour) {
  SurfaceMesh m = cube();
  m.points.push_back(0.5, 0, 0);  // m = point 8, exactly on edge 0-1
  // Side quad {0, 1, 5, 4} is facets 4 (0,1,5) and 5 (0,5,4): split facet 4 at m.
  const std::uint32_t side[6] = {0, 8, 5, 8, 1, 5};
  std::copy(side, side + 3, m.tris.begin() + 12);
  m.tris.insert(m.tris.end(), side + 3, side + 6);
  m.tris.insert(m.tris.end(), {0, 1, 8});  // the cap, facet 13
  EXPECT_EQ(defect_of(m), SurfaceError::Defect::degenerate);
  SurfaceRepairOptions o;
  o.degenerate = true;
  const SurfaceRepairReport r = repair_and_check(m, o, 14);
  EXPECT_EQ(r.split_caps, 1u);
  EXPECT_EQ(r.unfixed_caps, 0u);
  EXPECT_NE(r.notes.at(0).find("facets 13"), std::string::npos) << r.notes[0];
}

TEST(SurfaceRepair, NothingAskedNothingChanged) {
  SurfaceMesh m = cube();
  std::swap(m.tris[1], m.tris[2]);
  SurfaceRepairReport r;
  EXPECT_EQ(repair_surface(m, {}, r).tris, m.tris);
  EXPECT_FALSE(r.changed());
  // Non-finite or out-of-range input is left to validation, which names it.
  m.tris[0] = 99;
  EXPECT_EQ(repair_surface(m, parse_surface_repairs("all", "x"), r).tris, m.tris);
}

TEST(SurfaceRepair, ParseNames) {
  const SurfaceRepairOptions a = parse_surface_repairs("degenerate,orientation", "--repair");
  EXPECT_TRUE(a.degenerate && a.orientation && !a.duplicates);
  const SurfaceRepairOptions all = parse_surface_repairs("all", "--repair");
  EXPECT_TRUE(all.degenerate && all.duplicates && all.orientation);
  EXPECT_FALSE(parse_surface_repairs("", "--repair").any());
  EXPECT_FALSE(parse_surface_repairs("all,none", "--repair").any());
  try {
    parse_surface_repairs("orientaton", "--repair");
    ADD_FAILURE();
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown repair 'orientaton'"), std::string::npos) << e.what();
  }
}

// Through the pipeline: refused with a hint without the repair, meshed with it, and the change
// reported in the summary.
TEST(SurfaceRepair, JobHintsAtTheRepairAndReportsIt) {
  SurfaceMesh m = cube();
  std::swap(m.tris[3 * 5 + 1], m.tris[3 * 5 + 2]);
  const std::string stl = test::scratch_path("surface_repair", ".stl");
  write_stl(m, stl);
  MeshJob job;
  job.name = "flipped";
  job.input = stl;
  job.sizing.max_size = 0.5;
  MeshJobResult r = run_mesh_job(job);
  EXPECT_EQ(r.code, ExitCode::geometry);
  const std::string msg = r.summary["error"]["message"];
  EXPECT_NE(msg.find("'--repair orientation'"), std::string::npos) << msg;
  job.repair.orientation = true;
  r = run_mesh_job(job);
  ASSERT_TRUE(r.ok()) << r.summary.dump(1);
  EXPECT_EQ(r.summary["repairs"]["flipped"], 1);
  EXPECT_NE(r.summary["notices"].dump().find("repair: flipped 1 facet(s)"), std::string::npos);
  EXPECT_NEAR(r.summary["mesh_check"]["mesh_volume"].get<double>(), 1.0, 1e-9) << r.summary["mesh_check"].dump();
}

}  // namespace
}  // namespace kdmesh
