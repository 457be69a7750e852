// kdmesh — verify a Delaunay tetrahedralization: exact validity, TetGen 1.5, CGAL 5.5.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "tools/app/delaunay_verify.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <mutex>
#include <sstream>

#include "core/error.h"
#include "core/timer.h"
#include "mesher/delaunay/delaunay.h"
#include "mesher/reference/delaunay_check.h"
#include "mesher/order/order.h"
#include "mesher/reference/reference_delaunay.h"
#include "mesher/reference/tet_compare.h"

namespace kdmesh {

namespace {

std::string tets_str(const std::vector<std::uint32_t>& t) {
  std::ostringstream s;
  for (std::size_t i = 0; i + 3 < t.size(); i += 4)
    s << (i ? ", " : "") << "(" << t[i] << " " << t[i + 1] << " " << t[i + 2] << " " << t[i + 3] << ")";
  return s.str();
}

/// One cross-kernel comparison. In general position (no perturbation-only ties) the Delaunay
/// tetrahedralization is unique, so the tet sets must be identical; otherwise correct kernels
/// may break ties differently and only the invariants (volume) must agree.
nlohmann::json compare_with(const std::string& name, const PointSet& pts,
                            const std::vector<std::uint32_t>& ours,
                            const std::vector<std::uint32_t>& theirs, bool general_position,
                            double seconds, std::ostream& out, bool& ok) {
  const TetComparison c = compare_tets(pts, ours, theirs);
  const double rel = std::fabs(c.volume_a - c.volume_b) / std::max(std::fabs(c.volume_a), 1e-300);
  const bool pass = general_position ? c.same_set() : rel <= 1e-9;
  ok = ok && pass;
  out << "  " << std::left << std::setw(8) << name << (pass ? "ok " : "FAIL ") << " tets "
      << c.tets_a << " vs " << c.tets_b << ", volume rel. diff " << std::setprecision(3) << rel
      << ", "
      << (c.same_set() ? "identical tet set"
                       : std::to_string(c.only_in_a) + " tets only ours, " +
                             std::to_string(c.only_in_b) + " only theirs")
      << (general_position ? "" : " (cospherical ties: sets may differ)") << " [" << seconds
      << " s]\n";
  if (!c.same_set() && general_position)
    out << "    only ours: " << tets_str(c.example_only_a) << "\n    only " << name << ": "
        << tets_str(c.example_only_b) << "\n";
  return {{"pass", pass},          {"tets", c.tets_a},          {"reference_tets", c.tets_b},
          {"volume", c.volume_a},  {"reference_volume", c.volume_b},
          {"identical", c.same_set()}, {"only_ours", c.only_in_a}, {"only_reference", c.only_in_b},
          {"seconds", seconds}};
}

}  // namespace

DelaunayVerification verify_delaunay(const PointSet& pts, const Triangulation& tri,
                                     const std::vector<std::uint32_t>& canon_tets,
                                     const DelaunayVerifyOptions& o) {
  auto stage = [&](const std::string& s) {
    if (o.stage) o.stage(s);
  };
  std::ostringstream out;
  bool ok = true;
  nlohmann::json j;
  // Volumes are compared with the largest coordinate scaled into [0.5, 1) (a power-of-two
  // rescaling; same tets), so that neither huge nor mixed huge and tiny inputs overflow.
  const int vk = magnitude_scale_exponent(pts);
  const PointSet unit = vk != 0 ? scaled_copy(pts, vk) : pts;
  stage("check: exact validity");
  Stopwatch clock;
  const ValidityReport v = check_delaunay(pts, tri);
  const bool general = v.tie_faces == 0;
  out << "check:\n  validity " << (v.ok() ? "ok " : "FAIL ") << " " << v.finite_tets << " tets, "
      << v.hull_faces << " hull faces, adjacency faults " << v.asymmetric_adjacencies
      << ", inverted " << v.bad_orientation << ", non-Delaunay faces " << v.non_delaunay_faces
      << ", tie faces " << v.tie_faces << ", volume " << std::setprecision(12);
  if (std::isfinite(v.volume) && std::isfinite(v.hull_volume))
    out << v.volume << " vs hull " << v.hull_volume;
  else  // beyond double range in the input's units: say so, with the compared values
    out << v.scaled_volume << " vs hull " << v.scaled_hull_volume << " (in units of 2^" << -v.volume_exponent
        << ")";
  out << std::setprecision(6) << " [" << clock.seconds() << " s]\n";
  for (const std::string& p : v.problems) out << "    " << p << "\n";
  ok = ok && v.ok();
  j["validity"] = {{"pass", v.ok()},
                   {"finite_tets", v.finite_tets},
                   {"hull_faces", v.hull_faces},
                   {"asymmetric_adjacencies", v.asymmetric_adjacencies},
                   {"bad_orientation", v.bad_orientation},
                   {"non_delaunay_faces", v.non_delaunay_faces},
                   {"tie_faces", v.tie_faces},
                   {"volume", v.volume},
                   {"hull_volume", v.hull_volume},
                   {"problems", v.problems},
                   {"seconds", clock.seconds()}};
  j["general_position"] = general;

  if (o.references) {
    if (!tetgen_available()) {
      // `delaunay --check` is the exact check plus every reference this build has; a TetGen
      // check asked for by name (mesh --check tetgen) is refused before meshing instead.
      const std::string why = without_tetgen_message("the TetGen comparison");
      out << "  tetgen   skipped: " << why << "\n";
      j["tetgen"] = {{"pass", true}, {"skipped", why}};
    } else try {
      stage("check: TetGen 1.5");
      ReferenceResult tg;
      {
        // TetGen 1.5 keeps its predicates' filter bounds in globals set per call (exactinit):
        // concurrent calls (batch jobs run in threads) would race, so they take turns.
        static std::mutex tetgen_mutex;
        std::lock_guard<std::mutex> lock(tetgen_mutex);
        tg = tetgen_delaunay(pts);
      }
      j["tetgen"] = compare_with("tetgen", unit, canon_tets, tg.tets, general, tg.seconds, out, ok);
    } catch (const GeometryError& e) {
      // Input TetGen 1.5 cannot take (e.g. a slab thinner than its tolerance) is valid input
      // for the kernel: say that this comparison was skipped, and why; the others still decide.
      out << "  tetgen   skipped: " << e.what() << "\n";
      j["tetgen"] = {{"pass", true}, {"skipped", e.what()}};
    }
    if (!o.compare_kdmesh_kernel) {
      stage("check: CGAL 5.5");
      const ReferenceResult cg = cgal_delaunay(pts, nullptr);
      j["cgal"] = compare_with("cgal", unit, canon_tets, cg.tets, general, cg.seconds, out, ok);
    } else {
      stage("check: kdmesh kernel");
      Stopwatch c2;
      const DelaunayResult r = delaunay(pts, make_order(pts, {OrderKind::kd_bfs, o.seed, 0.125}));
      auto ours = finite_tets(r.tri);
      const auto canon = canonical_point_ids(pts);
      for (auto& x : ours) x = canon[x];
      j["kdmesh"] = compare_with("kdmesh", unit, canon_tets, ours, general, c2.seconds(), out, ok);
    }
  }
  j["pass"] = ok;
  return {ok, std::move(j), out.str()};
}

}  // namespace kdmesh
