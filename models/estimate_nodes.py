#!/usr/bin/env python3
# kdmesh — estimates the node count of each job of a kdmesh batch file (pure Python + PyYAML).
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Usage: estimate_nodes.py [--columns N] BATCH.yaml...

For every job: N ~= integral over the solid of 1 / (0.7 h(x)^3) dx, the node density of a
mesh whose edge length is h (an estimate: the lead calibrates the 0.7 against the pipeline),
with the sizing field of sizing/sizing_field.h:
    h(x) = max(h_min, min(h_max, min over zones (size_z + g * d(x, zone)))).
Distances: plane = distance to the whole plane (the real zone is the plane clipped to the
solid, so this slightly overestimates N), segment/polyline/point exact, box/ball 0 inside,
sharp_edges = distance to the surface edges whose facet normals differ by >= angle.

Integration: columns parallel to z on a grid of about N cells over the xy bounding box, each
cell split in four, recursively, while it is wider than h_low / (4 g) (h_low: the smallest h
along a probe column near its centre); each cell that is not split is then sampled by one
column at a seeded random point of it (unbiased, reproducible). The inside intervals of a
column come from its crossings with the facets (parity), and the density is integrated
along them with steps of h/3 (midpoint rule).
Needs PyYAML (Debian: python3-yaml).
"""
import math
import os
import random
import sys
from collections import defaultdict

import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_stl import read_surface  # noqa: E402

DENSITY = 0.7  # nodes per unit volume = 1 / (DENSITY * h^3)


def seg_dist(p, a, b):
    ab = [b[i] - a[i] for i in range(3)]
    ap = [p[i] - a[i] for i in range(3)]
    L2 = sum(x * x for x in ab)
    t = 0.0 if L2 == 0 else max(0.0, min(1.0, sum(ab[i] * ap[i] for i in range(3)) / L2))
    return math.dist(p, [a[i] + t * ab[i] for i in range(3)])


def sharp_edges(tris, angle_deg):
    """Surface edges whose two facet normals differ by >= angle_deg (border edges too)."""
    def normal(t):
        a, b, c = t
        u = [b[i] - a[i] for i in range(3)]
        v = [c[i] - a[i] for i in range(3)]
        n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
        L = math.sqrt(sum(x * x for x in n)) or 1.0
        return [x / L for x in n]
    by_edge = defaultdict(list)
    for t in tris:
        n = normal(t)
        for k in range(3):
            a, b = t[k], t[(k + 1) % 3]
            by_edge[(min(a, b), max(a, b))].append(n)
    cosl = math.cos(math.radians(angle_deg))
    out = []
    for e, ns in by_edge.items():
        if len(ns) != 2 or sum(ns[0][i] * ns[1][i] for i in range(3)) <= cosl:
            out.append(e)
    return out


class Field:
    def __init__(self, job, tris):
        self.hmax = float(job["size"])
        self.hmin = float(job.get("min_size", self.hmax / 1000))
        self.g = float(job.get("gradation", 0.3))
        self.zones = []
        for z in job.get("zones", []) or []:
            s, kind = float(z["size"]), z["type"]
            reach = (self.hmax - s) / self.g  # beyond this the zone does not matter
            if kind == "plane":
                o, n = z["origin"], z["normal"]
                L = math.sqrt(sum(x * x for x in n))
                n = [x / L for x in n]
                f = (lambda o, n: lambda p: abs(sum((p[i] - o[i]) * n[i] for i in range(3))))(o, n)
            elif kind == "segment":
                f = (lambda a, b: lambda p: seg_dist(p, a, b))(z["from"], z["to"])
            elif kind == "polyline":
                pts = z["points"]
                f = (lambda pts: lambda p: min(seg_dist(p, pts[i], pts[i + 1])
                                               for i in range(len(pts) - 1)))(pts)
            elif kind == "point":
                f = (lambda c: lambda p: math.dist(p, c))(z["at"])
            elif kind == "ball":
                f = (lambda c, r: lambda p: max(0.0, math.dist(p, c) - r))(z["center"],
                                                                           z["radius"])
            elif kind == "box":
                lo, hi = z["min"], z["max"]
                f = (lambda lo, hi: lambda p: math.sqrt(sum(
                    max(lo[i] - p[i], 0.0, p[i] - hi[i]) ** 2 for i in range(3))))(lo, hi)
            elif kind == "sharp_edges":
                f = self._edge_field(sharp_edges(tris, float(z.get("angle", 30))), reach)
            else:
                raise ValueError(f"zone type {kind!r} unknown")
            self.zones.append((s, f))

    def _edge_field(self, edges, reach):
        cell = max(reach, 1e-9)
        grid = defaultdict(list)
        for a, b in edges:
            lo = [math.floor(min(a[i], b[i]) / cell) for i in range(3)]
            hi = [math.floor(max(a[i], b[i]) / cell) for i in range(3)]
            for i in range(lo[0], hi[0] + 1):
                for j in range(lo[1], hi[1] + 1):
                    for k in range(lo[2], hi[2] + 1):
                        grid[(i, j, k)].append((a, b))

        def f(p):
            c = [math.floor(p[i] / cell) for i in range(3)]
            best = math.inf
            for i in (-1, 0, 1):
                for j in (-1, 0, 1):
                    for k in (-1, 0, 1):
                        for a, b in grid.get((c[0] + i, c[1] + j, c[2] + k), ()):
                            best = min(best, seg_dist(p, a, b))
            return best
        return f

    def __call__(self, p):
        h = self.hmax
        for s, f in self.zones:
            h = min(h, s + self.g * f(p))
        return max(self.hmin, h)


def estimate(job, base_dir, columns, seed=1):
    paths = [os.path.join(base_dir, b["input"]) for b in job["bodies"]] if "bodies" in job \
        else [os.path.join(base_dir, job["input"])]
    scale = float(job.get("scale", 1.0))
    # Touching bodies fill their union: the columns count each body's own inside length.
    tris = [tuple(tuple(scale * c for c in p) for p in t) for path in paths for t in read_surface(path)]
    field = Field(job, tris)
    xs = [p[0] for t in tris for p in t]
    ys = [p[1] for t in tris for p in t]
    x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
    nx = max(1, round(math.sqrt(columns * (x1 - x0) / (y1 - y0))))
    ny = max(1, round(columns / nx))
    dx, dy = (x1 - x0) / nx, (y1 - y0) / ny
    bins = defaultdict(list)
    for t in tris:
        i0 = math.floor((min(p[0] for p in t) - x0) / dx)
        i1 = math.floor((max(p[0] for p in t) - x0) / dx)
        j0 = math.floor((min(p[1] for p in t) - y0) / dy)
        j1 = math.floor((max(p[1] for p in t) - y0) / dy)
        for i in range(max(i0, 0), min(i1, nx - 1) + 1):
            for j in range(max(j0, 0), min(j1, ny - 1) + 1):
                bins[(i, j)].append(t)

    def column(x, y, i, j):
        """(integral of the density, inside length, min h) along the column at (x, y)."""
        zs = []
        for a, b, c in bins.get((i, j), ()):
            # barycentric coordinates of (x, y) in the xy projection
            d = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
            if d == 0:
                continue
            u = ((b[0] - x) * (c[1] - y) - (b[1] - y) * (c[0] - x)) / d
            v = ((c[0] - x) * (a[1] - y) - (c[1] - y) * (a[0] - x)) / d
            w = 1 - u - v
            if u >= 0 and v >= 0 and w >= 0:
                zs.append(u * a[2] + v * b[2] + w * c[2])
        zs.sort()
        dens, length, hlow = 0.0, 0.0, field.hmax
        for k in range(0, len(zs) - 1, 2):
            za, zb = zs[k], zs[k + 1]
            length += zb - za
            z = za
            while z < zb:
                step = min(field((x, y, z)) / 3, zb - z)
                hm = field((x, y, z + step / 2))
                hlow = min(hlow, hm)
                dens += step / (DENSITY * hm ** 3)
                z += step
        return dens, length, hlow

    # Adaptive quadrature over xy: a cell is split in four while it is wider than
    # h_low / (4 g), h_low the smallest h met along a probe column at a fixed point near the
    # cell's centre (the density varies on the scale h / (3 g) across a zone), down to 1/256
    # of a base cell. A cell that is not split is estimated from a second column at a seeded
    # random point of it: as the split decision does not depend on that sample, the sum is
    # an unbiased estimate (a random probe reused after the decision would not be).
    rng = random.Random(seed)

    def cell(cx0, cy0, w, hgt, i, j, depth):
        probe = column(cx0 + 0.5137 * w, cy0 + 0.4781 * hgt, i, j)
        if depth < 8 and max(w, hgt) > probe[2] / (4 * field.g):
            out = [0.0, 0.0]
            for sx in (0, 1):
                for sy in (0, 1):
                    r = cell(cx0 + sx * w / 2, cy0 + sy * hgt / 2, w / 2, hgt / 2, i, j,
                             depth + 1)
                    out[0] += r[0]
                    out[1] += r[1]
            return out
        dens, length, _ = column(cx0 + rng.random() * w, cy0 + rng.random() * hgt, i, j)
        return [dens * w * hgt, length * w * hgt]

    total = 0.0
    vol = 0.0
    for i in range(nx):
        for j in range(ny):
            r = cell(x0 + i * dx, y0 + j * dy, dx, dy, i, j, 0)
            total += r[0]
            vol += r[1]
    return total, vol, field


def main(argv):
    columns = 5000
    files = []
    it = iter(argv)
    for a in it:
        if a == "--columns":
            columns = int(next(it))
        else:
            files.append(a)
    if not files:
        print(__doc__)
        return 2
    for path in files:
        with open(path) as f:
            doc = yaml.safe_load(f)
        defaults = doc.get("defaults", {}) or {}
        for job in doc["jobs"]:
            j = dict(defaults)
            j.update(job)
            n, vol, field = estimate(j, os.path.dirname(os.path.abspath(path)), columns)
            uniform = vol / (DENSITY * field.hmax ** 3)
            print(f"{path}: job {j['name']}: volume {vol:.4g}, h_max {field.hmax:g}: "
                  f"uniform {uniform:,.0f} nodes; with zones ~{n:,.0f} nodes")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
