// kdmesh — which paths of a run name the same file: an output that is an input, or two outputs
// that are one file, compared by device and inode (not by spelling).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace kdmesh {

/// One path a run reads or writes; `label` names it in messages (e.g. "--summary").
struct PathUse {
  std::string path;
  bool output = false;
  std::string label;
};

/// Two uses (indices into the list, first < second) that name the same file.
struct PathClash {
  std::size_t first = 0, second = 0;
};

/// The first pair of uses naming one file where at least one of the two is an output (two
/// inputs may share a file). Identity: an existing output is its directory entry (lstat:
/// replacing a symbolic link does not touch its target); an input is both its entry and the
/// file it resolves to; a path that does not exist yet is its parent directory's device and
/// inode plus its file name (or, if the parent does not exist either, its absolute normal form).
/// Hard links, "./a" vs "a", and symbolic links to an input are therefore all caught.
std::optional<PathClash> find_path_clash(const std::vector<PathUse>& uses);

/// "<label> 'path' and <label> 'path' are the same file" for a clash, plus why it matters.
std::string describe_path_clash(const std::vector<PathUse>& uses, const PathClash& clash);

}  // namespace kdmesh
