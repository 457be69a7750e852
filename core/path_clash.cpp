// SPDX-License-Identifier: AGPL-3.0-or-later
#include "core/path_clash.h"

#include <sys/stat.h>

#include <filesystem>
#include <map>
#include <tuple>

namespace kdmesh {

namespace {

namespace fs = std::filesystem;

/// A file: (device, inode) of an existing one, or (parent device, parent inode, name) of one
/// to be created, or the absolute normal path when even the parent is missing.
struct Identity {
  int kind = 0;  // 0 existing file, 1 name in an existing directory, 2 path
  unsigned long long dev = 0, ino = 0;
  std::string name;
  bool operator<(const Identity& o) const {
    return std::tie(kind, dev, ino, name) < std::tie(o.kind, o.dev, o.ino, o.name);
  }
  bool operator==(const Identity& o) const {
    return kind == o.kind && dev == o.dev && ino == o.ino && name == o.name;
  }
};

Identity of_stat(const struct stat& st) {
  return {0, static_cast<unsigned long long>(st.st_dev), static_cast<unsigned long long>(st.st_ino), {}};
}

/// The identity of a path that does not exist.
Identity of_missing(const std::string& path) {
  const fs::path p(path);
  const fs::path parent = p.has_parent_path() ? p.parent_path() : fs::path(".");
  struct stat st {};
  if (::stat(parent.c_str(), &st) == 0)
    return {1, static_cast<unsigned long long>(st.st_dev), static_cast<unsigned long long>(st.st_ino),
            p.filename().string()};
  std::error_code ec;
  fs::path a = fs::absolute(p, ec);
  return {2, 0, 0, (ec ? p : a).lexically_normal().string()};
}

/// Every identity a use may stand for.
std::vector<Identity> identities(const PathUse& u) {
  std::vector<Identity> ids;
  struct stat st {};
  if (::lstat(u.path.c_str(), &st) != 0) return {of_missing(u.path)};
  ids.push_back(of_stat(st));
  if (!u.output && S_ISLNK(st.st_mode) && ::stat(u.path.c_str(), &st) == 0) ids.push_back(of_stat(st));
  return ids;
}

}  // namespace

std::optional<PathClash> find_path_clash(const std::vector<PathUse>& uses) {
  constexpr std::size_t kNone = std::size_t(-1);
  struct Seen {
    std::size_t any = kNone, output = kNone;  // the first use, and the first output, of a file
  };
  std::map<Identity, Seen> seen;
  for (std::size_t j = 0; j < uses.size(); ++j) {
    const std::vector<Identity> ids = identities(uses[j]);
    for (const Identity& id : ids) {
      Seen& s = seen[id];
      const std::size_t other = uses[j].output ? s.any : s.output;
      if (other != kNone && other != j) return PathClash{other, j};
    }
    for (const Identity& id : ids) {
      Seen& s = seen[id];
      if (s.any == kNone) s.any = j;
      if (uses[j].output && s.output == kNone) s.output = j;
    }
  }
  return std::nullopt;
}

std::string describe_path_clash(const std::vector<PathUse>& uses, const PathClash& c) {
  const PathUse& a = uses[c.first];
  const PathUse& b = uses[c.second];
  std::string s = a.label + " '" + a.path + "' and " + b.label + " '" + b.path + "' are the same file";
  if (a.output && b.output)
    s += ": two outputs cannot share a file";
  else
    s += ": an output cannot replace an input";
  return s;
}

}  // namespace kdmesh
