// SPDX-License-Identifier: AGPL-3.0-or-later
// kdmesh — the CGAL Mesh_3 column of tools/bench/real_parts.sh: meshes one closed surface with
// CGAL's Polyhedral_mesh_domain_with_features_3 (sharp edges detected and protected), writes a
// MEDIT .mesh. Built only with -DKDMESH_BENCH_MESH3=ON (its compile takes minutes).
//
//   mesh3_part SURFACE H OUT.mesh [FEATURE_ANGLE_DEG]
//
// Criteria (all from H): edge_size = H, facet_size = H, facet_angle = 25 deg,
// facet_distance = H/10, cell_size = H, cell_radius_edge_ratio = 3; then perturb and exude
// (CGAL's defaults for their time limits and bounds), no Lloyd/ODT. Features: dihedral angle
// below 180 - FEATURE_ANGLE_DEG (default 60, CGAL's detect_features default) is a sharp edge.
// Prints one JSON line (vertices, tets, seconds). Exit 1 on a surface CGAL cannot read or that
// is not a closed polyhedron, 2 on usage.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/File_medit.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_polyhedron_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polygon_mesh_processing/IO/polygon_mesh_io.h>
#include <CGAL/Polyhedral_mesh_domain_with_features_3.h>
#include <CGAL/make_mesh_3.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Polyhedron = CGAL::Mesh_polyhedron_3<K>::type;
using Domain = CGAL::Polyhedral_mesh_domain_with_features_3<K>;
using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr, Domain::Corner_index,
                                                     Domain::Curve_index>;
using Criteria = CGAL::Mesh_criteria_3<Tr>;

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4 || argc > 5) {
    std::fprintf(stderr, "usage: %s SURFACE H OUT.mesh [FEATURE_ANGLE_DEG]\n", argv[0]);
    return 2;
  }
  const std::string in = argv[1];
  const double h = std::atof(argv[2]);
  const std::string out = argv[3];
  const double feature_angle = argc == 5 ? std::atof(argv[4]) : 60.0;
  if (!(h > 0)) {
    std::fprintf(stderr, "mesh3_part: H must be > 0\n");
    return 2;
  }
  const auto t0 = std::chrono::steady_clock::now();
  Polyhedron poly;
  if (!CGAL::Polygon_mesh_processing::IO::read_polygon_mesh(in, poly) || poly.empty() ||
      !poly.is_closed()) {
    std::fprintf(stderr, "mesh3_part: %s is not a readable closed polyhedron\n", in.c_str());
    return 1;
  }
  Domain domain(poly);
  domain.detect_features(feature_angle);
  namespace p = CGAL::parameters;
  Criteria criteria(p::edge_size = h, p::facet_angle = 25.0, p::facet_size = h,
                    p::facet_distance = h / 10.0, p::cell_radius_edge_ratio = 3.0,
                    p::cell_size = h);
  C3t3 c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria, p::no_lloyd(), p::no_odt(),
                                      p::perturb(), p::exude());
  std::ofstream os(out);
  CGAL::output_to_medit(os, c3t3);  // CGAL 5.5: IO::write_MEDIT takes a triangulation
  os.close();
  if (!os) {
    std::fprintf(stderr, "mesh3_part: cannot write %s\n", out.c_str());
    return 1;
  }
  const double secs =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("{\"vertices\": %zu, \"tets\": %zu, \"seconds\": %.3f}\n",
              static_cast<std::size_t>(c3t3.triangulation().number_of_vertices()),
              static_cast<std::size_t>(c3t3.number_of_cells_in_complex()), secs);
  return 0;
}
