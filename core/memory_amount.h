// kdmesh — memory amounts: parsing limits such as "8G", printing byte counts, the machine's RAM.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <string>

namespace kdmesh {

/// "1.23 GB", "456 MB", "789 kB" (decimal units).
std::string format_bytes(double bytes);

/// Parses a memory limit: a number with an optional unit k, M, G, T (decimal, optionally
/// followed by B, case-insensitive; "8G" = 8e9 bytes), a bare byte count, or "none" (no limit,
/// returned as -1). Throws UsageError naming `what` for anything else or for a value <= 0.
double parse_memory_amount(const std::string& text, const std::string& what);

/// The machine's physical memory in bytes (0 if unknown).
double physical_memory_bytes();

/// The limit in force for a parsed --max-memory value: `option` > 0 as is, 0 (not given) the
/// machine's physical memory, < 0 ("none") no limit, returned as 0.
double effective_memory_limit(double option);

}  // namespace kdmesh
