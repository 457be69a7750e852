// kdmesh — opt-in safe repairs of a triangle surface before validation
// (pipeline stage: SurfaceMesh -> SurfaceMesh, run before prepare_surface).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/surface_mesh.h"

namespace kdmesh {

/// Which repairs to make. Each is "safe": it changes no point and leaves the solid the
/// surface bounds unchanged (the same point set is enclosed), or it refuses to act.
struct SurfaceRepairOptions {
  /// Zero-area facets: a facet with a repeated corner id is removed; a facet whose three
  /// distinct corners are exactly collinear (b strictly between a and c) is removed and the
  /// facet across its long edge a-c is split at b into two, which cover exactly what it did.
  bool degenerate = false;
  /// Copies of a facet with the same 3 points in the same cyclic order are removed (the first
  /// in file order is kept). Copies facing opposite ways (a two-sided sheet) are left alone:
  /// removing them is not safe, and validation reports them.
  bool duplicates = false;
  /// In each connected piece of the surface (through edges with exactly two facets), the
  /// facets that disagree with the majority orientation are flipped. Pieces that are not
  /// orientable are left alone (validation reports them).
  bool orientation = false;

  bool any() const { return degenerate || duplicates || orientation; }
};

/// What the repairs changed. Facet ids are those of the input surface.
struct SurfaceRepairReport {
  std::size_t removed_collapsed = 0;   ///< facets with a repeated corner, removed
  std::size_t split_caps = 0;          ///< collinear facets removed by splitting their neighbour
  std::size_t unfixed_caps = 0;        ///< collinear facets left (no usable neighbour)
  std::size_t removed_duplicates = 0;  ///< same-orientation copies removed
  std::size_t flipped = 0;             ///< facets flipped to agree with their piece
  std::vector<std::string> notes;      ///< one line per kind of change, naming facets
  bool changed() const { return removed_collapsed + split_caps + removed_duplicates + flipped > 0; }
  /// Adds another report's counts and notes (several bodies' repairs reported as one).
  void add(const SurfaceRepairReport& o) {
    removed_collapsed += o.removed_collapsed;
    split_caps += o.split_caps;
    unfixed_caps += o.unfixed_caps;
    removed_duplicates += o.removed_duplicates;
    flipped += o.flipped;
    notes.insert(notes.end(), o.notes.begin(), o.notes.end());
  }
};

/// "degenerate,duplicates,orientation" / "all" / "none" -> options; UsageError naming `what`
/// and the valid names otherwise. (Inline: the config loader uses it without the repairs.)
inline SurfaceRepairOptions parse_surface_repairs(const std::string& list, const std::string& what) {
  SurfaceRepairOptions o;
  std::stringstream s(list);
  for (std::string item; std::getline(s, item, ',');) {
    if (item == "degenerate") o.degenerate = true;
    else if (item == "duplicates") o.duplicates = true;
    else if (item == "orientation") o.orientation = true;
    else if (item == "all") o.degenerate = o.duplicates = o.orientation = true;
    else if (item == "none") o = {};
    else
      throw UsageError(what + ": unknown repair '" + item +
                       "'; valid: degenerate, duplicates, orientation, all, none");
  }
  return o;
}

/// Applies the repairs `options` asks for, in the order degenerate, duplicates, orientation,
/// and returns the repaired surface (points unchanged; facets removed, split or flipped;
/// facet order otherwise kept, split-off halves appended). Exact predicates only.
SurfaceMesh repair_surface(SurfaceMesh mesh, const SurfaceRepairOptions& options, SurfaceRepairReport& report);

}  // namespace kdmesh
