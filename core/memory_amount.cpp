// kdmesh — memory amounts.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "core/memory_amount.h"

#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstdio>

#include "core/error.h"

namespace kdmesh {

std::string format_bytes(double bytes) {
  if (!std::isfinite(bytes)) return "an unbounded amount";
  const char* units[] = {"bytes", "kB", "MB", "GB", "TB", "PB"};
  int u = 0;
  while (bytes >= 1000 && u < 5) {
    bytes /= 1000;
    ++u;
  }
  char buf[64];
  std::snprintf(buf, sizeof buf, u == 0 ? "%.0f %s" : "%.3g %s", bytes, units[u]);
  return buf;
}

double parse_memory_amount(const std::string& text, const std::string& what) {
  if (text == "none") return -1;
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  std::string unit = text.substr(used);
  for (char& ch : unit) ch = char(std::toupper(static_cast<unsigned char>(ch)));
  if (unit.size() == 2 && unit[1] == 'B') unit.pop_back();
  double mult = 0;
  if (unit.empty() || unit == "B") mult = 1;
  else if (unit == "K") mult = 1e3;
  else if (unit == "M") mult = 1e6;
  else if (unit == "G") mult = 1e9;
  else if (unit == "T") mult = 1e12;
  if (used == 0 || mult == 0 || !(v > 0) || !std::isfinite(v))
    throw UsageError(what + ": '" + text + "' is not a memory amount (e.g. 8G, 512M, 2.5GB, none)");
  return v * mult;
}

double physical_memory_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? double(pages) * double(page) : 0;
}

double effective_memory_limit(double option) {
  return option < 0 ? 0 : option > 0 ? option : physical_memory_bytes();
}

}  // namespace kdmesh
