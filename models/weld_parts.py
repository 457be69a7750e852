#!/usr/bin/env python3
# kdmesh — makes the touching faces of an assembly's part STLs coincide exactly (pure Python).
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Usage: weld_parts.py TOL PART.stl...

OpenSCAD computes the same cylinder vertex of two parts along different paths (a primitive's
own transform in doubles, or CGAL's exact transform of a CSG result), and binary STL rounds both
to float32: coordinates meant to be equal differ by a float32 ulp (1e-6 mm on the gear box), so
faces meant to touch overlap or leave a gap, and kdmesh, which decides contact exactly, refuses
them. Touching faces share coordinates, not necessarily vertices (a shaft's side spans the
bearing ring and the gear's bore), so this works per coordinate: each x, y and z value of a
part moves to the smallest value of that axis among the earlier parts' (in argument order)
within TOL (model units) of it, and the part is rewritten in place (generate.sh sorts it again
with canonical_stl.py). Prints how many coordinates moved per part.
"""
import os
import struct
import sys


RECORD = struct.Struct("<12fH")


def read(path):
    with open(path, "rb") as f:
        data = f.read()
    n = struct.unpack_from("<I", data, 80)[0]
    return data[:80], [list(RECORD.unpack_from(data, 84 + 50 * k)) for k in range(n)]


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    tol = float(argv[0])
    seen = [{}, {}, {}]  # per axis: bucket -> earlier parts' values

    def bucket(v):
        return int(v // (4 * tol))

    for path in argv[1:]:
        header, facets = read(path)
        moved = 0
        mine = [set(), set(), set()]
        for rec in facets:
            for k in range(9):
                axis, v = k % 3, rec[3 + k]
                b = bucket(v)
                near = [q for d in (-1, 0, 1) for q in seen[axis].get(b + d, ()) if abs(q - v) <= tol]
                if near and min(near) != v:
                    rec[3 + k] = min(near)
                    moved += 1
                mine[axis].add(rec[3 + k])
        for axis in range(3):
            for v in mine[axis]:
                seen[axis].setdefault(bucket(v), []).append(v)
        tmp = path + ".weld-tmp"
        with open(tmp, "wb") as f:
            f.write(header)
            f.write(struct.pack("<I", len(facets)))
            for rec in facets:
                f.write(RECORD.pack(*rec))
        os.replace(tmp, path)
        print(f"weld: {path}: {moved} coordinate(s) moved onto an earlier part's")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
