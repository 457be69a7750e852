#!/usr/bin/env python3
# kdmesh — self-test of check_stl.py: it must accept a valid solid and reject each defect.
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Usage: test_check_stl.py   (exit 0 when every case behaves as expected)

Builds small ASCII STLs in a temporary directory: a unit cube (valid), and the cube with
one defect each (a flipped facet, a missing facet, everything flipped, a second cube
overlapping it, two crossing boxes, a second cube inside it, a second cube sharing a face
with it), and two
disjoint cubes 3 apart (valid; clearance exactly 3, derived from the coordinates).
"""
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_stl import check  # noqa: E402


def cube(o, s=1.0):
    """12 outward facets of the cube [o, o+s]^3 (counter-clockwise seen from outside)."""
    return box(o, tuple(c + s for c in o))


def box(lo, hi):
    """12 outward facets of the box [lo, hi]."""
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    v = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0),
         (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    quads = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (2, 3, 7, 6), (1, 2, 6, 5), (0, 4, 7, 3)]
    out = []
    for a, b, c, d in quads:
        out.append((v[a], v[b], v[c]))
        out.append((v[a], v[c], v[d]))
    return out


def write(path, tris):
    with open(path, "w") as f:
        f.write("solid t\n")
        for t in tris:
            f.write(" facet normal 0 0 0\n  outer loop\n")
            for p in t:
                f.write(f"   vertex {p[0]!r} {p[1]!r} {p[2]!r}\n")
            f.write("  endloop\n endfacet\n")
        f.write("endsolid t\n")


def main():
    base = cube((0, 0, 0))
    flipped_one = list(base)
    a, b, c = flipped_one[3]
    flipped_one[3] = (a, c, b)
    cases = [
        ("valid cube", base, True, "closed"),
        ("one facet flipped", flipped_one, False, "same direction"),
        ("one facet missing", base[:-1], False, "not closed"),
        ("all facets flipped", [(t[0], t[2], t[1]) for t in base], False, "volume"),
        ("overlapping cubes", base + cube((0.5, 0.5, 0.5)), False, "intersect"),
        # no corner of either box is inside the other: only the facet test can see it
        ("crossing boxes", box((0, 1, 1), (3, 2, 2)) + box((1, 0, 0.5), (2, 3, 2.5)), False,
         "intersect"),
        ("nested cubes", cube((0, 0, 0), 3) + cube((1, 1, 1)), False, "inside shell"),
        ("cubes sharing a face", base + cube((1, 0, 0)), False, "not closed"),
        ("disjoint cubes", base + cube((4, 0, 0)), True, "closed"),
    ]
    failures = 0
    with tempfile.TemporaryDirectory() as d:
        for name, tris, want_ok, expect in cases:
            path = os.path.join(d, name.replace(" ", "_") + ".stl")
            write(path, tris)
            rep = check(path, do_intersect=True, do_clearance=True)
            good = rep["ok"] == want_ok
            if good and not want_ok:
                good = any(expect in p for p in rep["problems"])
            if name == "disjoint cubes":
                # cube [0,1]^3 and [4,5]x[0,1]^2: the gap is 4 - 1 = 3
                gap = rep["clearance"][0]["min_distance"]
                good = good and abs(gap - 3.0) < 1e-12
            if name == "valid cube":
                good = good and abs(rep["volume"] - 1.0) < 1e-12
            print(f"{'ok  ' if good else 'FAIL'} {name}: ok={rep['ok']} "
                  f"{rep['problems'][:1]}")
            failures += not good
    print(f"{len(cases) - failures} passed, {failures} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
