#!/usr/bin/env python3
# kdmesh — rewrites a binary STL in a canonical, reproducible byte layout (pure Python).
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Usage: canonical_stl.py IN.stl OUT.stl NAME

OpenSCAD 2021.01 emits the same facets (same corners, same corner order) on every run, but
in a run-dependent facet order. This sorts the facets by their corner coordinates (a total
order on the 50-byte records, ties only between identical records), keeps each facet's corner
order (its orientation), sets the 80-byte header to "kdmesh model NAME", and writes OUT
atomically (temporary file + rename). The result is byte-identical across runs.
"""
import os
import struct
import sys


def main(argv):
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    src, dst, name = argv
    with open(src, "rb") as f:
        data = f.read()
    if len(data) < 84:
        print(f"{src}: too short for a binary STL", file=sys.stderr)
        return 1
    n = struct.unpack_from("<I", data, 80)[0]
    if len(data) != 84 + 50 * n:
        print(f"{src}: size {len(data)} does not match {n} binary facets", file=sys.stderr)
        return 1
    recs = [data[84 + 50 * i: 134 + 50 * i] for i in range(n)]
    # key: the three corners (floats, in stored order), then the raw bytes (normal, attribute)
    recs.sort(key=lambda r: (struct.unpack_from("<9f", r, 12), r))
    header = f"kdmesh model {name}".encode("ascii")[:80].ljust(80, b"\0")
    tmp = f"{dst}.tmp-{os.getpid()}"
    with open(tmp, "wb") as f:
        f.write(header)
        f.write(struct.pack("<I", n))
        f.write(b"".join(recs))
    os.replace(tmp, dst)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
