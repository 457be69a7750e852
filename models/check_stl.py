#!/usr/bin/env python3
# kdmesh — independent validity checker for surface files (STL, PLY, OFF, OBJ); pure Python.
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Checks that a triangle surface bounds a valid solid, independently of kdmesh.

Usage: check_stl.py [--json] [--no-intersect] [--clearance] FILE...

Per file it reports facet/vertex counts and, per shell (edge-connected component): facet
count, signed volume (mm^3 if the file is in mm), bounding box, and the checks:
  - no degenerate facet (repeated vertex, or three exactly collinear corners);
  - closed and 2-manifold: every edge has exactly two facets, every vertex one fan;
  - consistently oriented: the two facets of every edge use it in opposite directions;
  - outward: every shell has positive volume and is not nested inside another shell
    (a negative shell would be a void; none of our models has one);
  - no self-intersection: no two facets meet except in their shared vertex or edge, tested
    with exact rational predicates (Python Fractions) behind a floating-point filter;
  - with --clearance: the minimum distance between distinct shells (vertex-facet and
    edge-edge pairs, floating point), i.e. the gap between disjoint bodies.
Vertices are welded by exact coordinates (STL stores each corner separately).
Exit status 0 when every check passes, 1 when one fails, 2 on an unreadable file.
"""
import json
import math
import os
import struct
import sys
from collections import defaultdict
from fractions import Fraction


# ---------------------------------------------------------------- readers

def read_stl(path):
    with open(path, "rb") as f:
        data = f.read()
    tris = []
    if len(data) >= 84:
        n = struct.unpack_from("<I", data, 80)[0]
        if 84 + 50 * n == len(data):
            for i in range(n):
                v = struct.unpack_from("<12f", data, 84 + 50 * i)
                tris.append((v[3:6], v[6:9], v[9:12]))
            return tris
    text = data.decode("ascii", errors="replace")
    cur = []
    for lineno, line in enumerate(text.splitlines(), 1):
        t = line.split()
        if t and t[0] == "vertex":
            if len(t) != 4:
                raise ValueError(f"{path}:{lineno}: malformed vertex line")
            cur.append(tuple(float(x) for x in t[1:4]))
        elif t and t[0] == "endloop":
            if len(cur) != 3:
                raise ValueError(f"{path}:{lineno}: facet with {len(cur)} vertices")
            tris.append(tuple(cur))
            cur = []
    if not tris:
        raise ValueError(f"{path}: no facets (neither binary nor ASCII STL)")
    return tris


def _fan(poly):
    return [(poly[0], poly[i], poly[i + 1]) for i in range(1, len(poly) - 1)]


def read_off(path):
    with open(path) as f:
        toks = []
        for line in f:
            toks.extend(line.split("#", 1)[0].split())
    head = toks.pop(0)
    if not head.endswith("OFF"):
        raise ValueError(f"{path}: not an OFF file (header {head!r})")
    nv, nf = int(toks[0]), int(toks[1])
    p = 3
    pts = []
    for _ in range(nv):
        pts.append(tuple(float(x) for x in toks[p:p + 3]))
        p += 3
    tris = []
    for _ in range(nf):
        k = int(toks[p])
        idx = [int(x) for x in toks[p + 1:p + 1 + k]]
        p += 1 + k
        tris.extend(tuple(pts[i] for i in t) for t in _fan(idx))
    return tris


def read_obj(path):
    pts, tris = [], []
    with open(path) as f:
        for line in f:
            t = line.split()
            if not t:
                continue
            if t[0] == "v":
                pts.append(tuple(float(x) for x in t[1:4]))
            elif t[0] == "f":
                idx = []
                for w in t[1:]:
                    i = int(w.split("/")[0])
                    idx.append(i - 1 if i > 0 else len(pts) + i)
                tris.extend(tuple(pts[i] for i in tri) for tri in _fan(idx))
    return tris


_PLY_FMT = {"char": "b", "int8": "b", "uchar": "B", "uint8": "B", "short": "h", "int16": "h",
            "ushort": "H", "uint16": "H", "int": "i", "int32": "i", "uint": "I",
            "uint32": "I", "float": "f", "float32": "f", "double": "d", "float64": "d"}


def read_ply(path):
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header")
    end = data.index(b"\n", end) + 1
    header = data[:end].decode("ascii").splitlines()
    fmt = None
    elements = []
    for line in header:
        t = line.split()
        if not t:
            continue
        if t[0] == "format":
            fmt = t[1]
        elif t[0] == "element":
            elements.append([t[1], int(t[2]), []])
        elif t[0] == "property":
            elements[-1][2].append(t[1:])
    body = data[end:]
    pts, tris = [], []
    if fmt == "ascii":
        toks = body.decode("ascii").split()
        p = 0
        for name, count, props in elements:
            for _ in range(count):
                rec = {}
                for pr in props:
                    if pr[0] == "list":
                        k = int(float(toks[p]))
                        rec[pr[-1]] = [int(float(x)) for x in toks[p + 1:p + 1 + k]]
                        p += 1 + k
                    else:
                        rec[pr[-1]] = float(toks[p])
                        p += 1
                _ply_store(name, rec, pts, tris)
    else:
        end_ch = "<" if fmt == "binary_little_endian" else ">"
        off = 0
        for name, count, props in elements:
            for _ in range(count):
                rec = {}
                for pr in props:
                    if pr[0] == "list":
                        cf, itf = _PLY_FMT[pr[1]], _PLY_FMT[pr[2]]
                        k = struct.unpack_from(end_ch + cf, body, off)[0]
                        off += struct.calcsize(cf)
                        rec[pr[-1]] = list(struct.unpack_from(end_ch + itf * k, body, off))
                        off += struct.calcsize(itf) * k
                    else:
                        c = _PLY_FMT[pr[0]]
                        rec[pr[-1]] = struct.unpack_from(end_ch + c, body, off)[0]
                        off += struct.calcsize(c)
                _ply_store(name, rec, pts, tris)
    return [tuple(pts[i] for i in t) for t in tris]


def _ply_store(name, rec, pts, tris):
    if name == "vertex":
        pts.append((rec["x"], rec["y"], rec["z"]))
    elif name == "face":
        idx = rec.get("vertex_indices", rec.get("vertex_index"))
        tris.extend(_fan(idx))


def read_surface(path):
    ext = os.path.splitext(path)[1].lower()
    if ext == ".stl":
        return read_stl(path)
    if ext == ".off":
        return read_off(path)
    if ext == ".obj":
        return read_obj(path)
    if ext == ".ply":
        return read_ply(path)
    raise ValueError(f"{path}: unknown extension {ext}")


# ---------------------------------------------------------------- exact predicates

def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _orient3d_exact(a, b, c, d):
    a, b, c, d = ([Fraction(x) for x in p] for p in (a, b, c, d))
    ax, ay, az = a[0] - d[0], a[1] - d[1], a[2] - d[2]
    bx, by, bz = b[0] - d[0], b[1] - d[1], b[2] - d[2]
    cx, cy, cz = c[0] - d[0], c[1] - d[1], c[2] - d[2]
    det = ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)
    return (det > 0) - (det < 0)


def orient3d(a, b, c, d):
    """Sign of det[a-d, b-d, c-d] (exact)."""
    ax, ay, az = a[0] - d[0], a[1] - d[1], a[2] - d[2]
    bx, by, bz = b[0] - d[0], b[1] - d[1], b[2] - d[2]
    cx, cy, cz = c[0] - d[0], c[1] - d[1], c[2] - d[2]
    det = ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)
    perm = (abs(ax) * (abs(by * cz) + abs(bz * cy)) + abs(ay) * (abs(bx * cz) + abs(bz * cx))
            + abs(az) * (abs(bx * cy) + abs(by * cx)))
    if abs(det) > 1e-14 * perm:  # generous version of Shewchuk's 7.8e-16 static bound
        return 1 if det > 0 else -1
    return _orient3d_exact(a, b, c, d)


def orient2d(a, b, c):
    det = (a[0] - c[0]) * (b[1] - c[1]) - (a[1] - c[1]) * (b[0] - c[0])
    perm = abs((a[0] - c[0]) * (b[1] - c[1])) + abs((a[1] - c[1]) * (b[0] - c[0]))
    if abs(det) > 1e-14 * perm:
        return 1 if det > 0 else -1
    a, b, c = ([Fraction(x) for x in p] for p in (a, b, c))
    det = (a[0] - c[0]) * (b[1] - c[1]) - (a[1] - c[1]) * (b[0] - c[0])
    return (det > 0) - (det < 0)


def _normal_axis(a, b, c):
    """Axis to drop when projecting triangle abc (largest |normal| component, exact)."""
    a, b, c = ([Fraction(x) for x in p] for p in (a, b, c))
    u, v = _sub(b, a), _sub(c, a)
    n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
    return max(range(3), key=lambda i: abs(n[i]))


def _proj(p, axis):
    return (p[1], p[2]) if axis == 0 else ((p[0], p[2]) if axis == 1 else (p[0], p[1]))


def collinear(a, b, c):
    return all(orient2d(_proj(a, ax), _proj(b, ax), _proj(c, ax)) == 0 for ax in range(3))


def _seg_seg_2d(p, q, a, b):
    """Closed 2-D segments pq and ab intersect."""
    o1, o2 = orient2d(p, q, a), orient2d(p, q, b)
    o3, o4 = orient2d(a, b, p), orient2d(a, b, q)
    if o1 * o2 < 0 and o3 * o4 < 0:
        return True

    def on(s, t, r):  # r on closed segment st, given collinear
        return (min(s[0], t[0]) <= r[0] <= max(s[0], t[0])
                and min(s[1], t[1]) <= r[1] <= max(s[1], t[1]))
    return ((o1 == 0 and on(p, q, a)) or (o2 == 0 and on(p, q, b))
            or (o3 == 0 and on(a, b, p)) or (o4 == 0 and on(a, b, q)))


def _point_in_tri_2d(p, a, b, c):
    s = orient2d(a, b, c)
    o = (orient2d(a, b, p), orient2d(b, c, p), orient2d(c, a, p))
    return all(x * s >= 0 for x in o)


def seg_tri(p, q, a, b, c):
    """Closed segment pq meets closed triangle abc (non-degenerate)."""
    op, oq = orient3d(a, b, c, p), orient3d(a, b, c, q)
    if op * oq > 0:
        return False
    if op == 0 and oq == 0:
        ax = _normal_axis(a, b, c)
        P, Q, A, B, C = (_proj(x, ax) for x in (p, q, a, b, c))
        return (_point_in_tri_2d(P, A, B, C) or _seg_seg_2d(P, Q, A, B)
                or _seg_seg_2d(P, Q, B, C) or _seg_seg_2d(P, Q, C, A))
    s1, s2, s3 = orient3d(p, q, a, b), orient3d(p, q, b, c), orient3d(p, q, c, a)
    return (s1 >= 0 and s2 >= 0 and s3 >= 0) or (s1 <= 0 and s2 <= 0 and s3 <= 0)


def tris_intersect(P, ti, tj):
    """Facets ti, tj (vertex-id triples) meet anywhere besides their shared vertices/edge."""
    shared = set(ti) & set(tj)
    A = [P[i] for i in ti]
    B = [P[i] for i in tj]
    if not shared:
        sb = [orient3d(A[0], A[1], A[2], x) for x in B]
        if all(x > 0 for x in sb) or all(x < 0 for x in sb):
            return False
        sa = [orient3d(B[0], B[1], B[2], x) for x in A]
        if all(x > 0 for x in sa) or all(x < 0 for x in sa):
            return False
        for k in range(3):
            if seg_tri(A[k], A[(k + 1) % 3], *B) or seg_tri(B[k], B[(k + 1) % 3], *A):
                return True
        return False
    if len(shared) == 3:  # the same three corners twice: coincident facets
        return True
    if len(shared) == 2:
        (u, v) = sorted(shared)
        c = next(i for i in ti if i not in shared)
        d = next(i for i in tj if i not in shared)
        if orient3d(P[u], P[v], P[c], P[d]) != 0:
            return False
        ax = _normal_axis(P[u], P[v], P[c])
        U, V, C, D = (_proj(P[x], ax) for x in (u, v, c, d))
        return orient2d(U, V, C) == orient2d(U, V, D)
    (s,) = shared
    oi = [i for i in ti if i != s]
    oj = [i for i in tj if i != s]
    # the edge opposite the shared vertex, against the other facet
    if seg_tri(P[oi[0]], P[oi[1]], *B) or seg_tri(P[oj[0]], P[oj[1]], *A):
        return True
    # an edge from the shared vertex lying in the other facet's plane, inside its angle
    for own, other in ((oi, oj), (oj, oi)):
        for w in own:
            if orient3d(P[s], P[other[0]], P[other[1]], P[w]) == 0:
                ax = _normal_axis(P[s], P[other[0]], P[other[1]])
                S, U1, U2, W = (_proj(P[x], ax) for x in (s, other[0], other[1], w))
                if orient2d(S, U1, U2) < 0:
                    U1, U2 = U2, U1
                if orient2d(S, U1, W) >= 0 and orient2d(S, W, U2) >= 0:
                    return True
    return False


# ---------------------------------------------------------------- geometry helpers

def _dot(u, v):
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


def _cross(u, v):
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])


def winding(P, tris, x):
    """Generalised winding number of the closed surface `tris` around point x (float)."""
    total = 0.0
    for t in tris:
        a, b, c = (_sub(P[i], x) for i in t)
        la, lb, lc = (math.sqrt(_dot(v, v)) for v in (a, b, c))
        num = _dot(a, _cross(b, c))
        den = la * lb * lc + _dot(a, b) * lc + _dot(b, c) * la + _dot(c, a) * lb
        total += 2 * math.atan2(num, den)
    return total / (4 * math.pi)


def point_tri_dist(p, a, b, c):
    """Euclidean distance from p to triangle abc (float)."""
    ab, ac, ap = _sub(b, a), _sub(c, a), _sub(p, a)
    d1, d2 = _dot(ab, ap), _dot(ac, ap)
    if d1 <= 0 and d2 <= 0:
        return math.dist(p, a)
    bp = _sub(p, b)
    d3, d4 = _dot(ab, bp), _dot(ac, bp)
    if d3 >= 0 and d4 <= d3:
        return math.dist(p, b)
    vc = d1 * d4 - d3 * d2
    if vc <= 0 and d1 >= 0 and d3 <= 0:
        v = d1 / (d1 - d3)
        return math.dist(p, tuple(a[i] + v * ab[i] for i in range(3)))
    cp = _sub(p, c)
    d5, d6 = _dot(ab, cp), _dot(ac, cp)
    if d6 >= 0 and d5 <= d6:
        return math.dist(p, c)
    vb = d5 * d2 - d1 * d6
    if vb <= 0 and d2 >= 0 and d6 <= 0:
        w = d2 / (d2 - d6)
        return math.dist(p, tuple(a[i] + w * ac[i] for i in range(3)))
    va = d3 * d6 - d5 * d4
    if va <= 0 and (d4 - d3) >= 0 and (d5 - d6) >= 0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return math.dist(p, tuple(b[i] + w * (c[i] - b[i]) for i in range(3)))
    denom = 1.0 / (va + vb + vc)
    v, w = vb * denom, vc * denom
    return math.dist(p, tuple(a[i] + ab[i] * v + ac[i] * w for i in range(3)))


def seg_seg_dist(p1, q1, p2, q2):
    d1, d2, r = _sub(q1, p1), _sub(q2, p2), _sub(p1, p2)
    a, e, f = _dot(d1, d1), _dot(d2, d2), _dot(d2, r)
    c, b = _dot(d1, r), _dot(d1, d2)
    denom = a * e - b * b
    s = min(max((b * f - c * e) / denom, 0.0), 1.0) if denom > 1e-300 else 0.0
    t = (b * s + f) / e
    if t < 0:
        t, s = 0.0, min(max(-c / a, 0.0), 1.0)
    elif t > 1:
        t, s = 1.0, min(max((b - c) / a, 0.0), 1.0)
    x = tuple(p1[i] + d1[i] * s for i in range(3))
    y = tuple(p2[i] + d2[i] * t for i in range(3))
    return math.dist(x, y)


# ---------------------------------------------------------------- the checks

class Grid:
    """Uniform grid of facet bounding boxes, for candidate pairs."""

    def __init__(self, P, tris, cell):
        self.cell = cell
        self.cells = defaultdict(list)
        for f, t in enumerate(tris):
            lo, hi = self.range(P, t, 0.0)
            for i in range(lo[0], hi[0] + 1):
                for j in range(lo[1], hi[1] + 1):
                    for k in range(lo[2], hi[2] + 1):
                        self.cells[(i, j, k)].append(f)

    def range(self, P, t, pad):
        c = self.cell
        lo = tuple(math.floor((min(P[i][a] for i in t) - pad) / c) for a in range(3))
        hi = tuple(math.floor((max(P[i][a] for i in t) + pad) / c) for a in range(3))
        return lo, hi


def check(path, do_intersect=True, do_clearance=False):
    raw = read_surface(path)
    ids = {}
    P = []
    tris = []
    for tri in raw:
        t = []
        for p in tri:
            p = tuple(float(x) for x in p)
            i = ids.get(p)
            if i is None:
                i = ids[p] = len(P)
                P.append(p)
            t.append(i)
        tris.append(tuple(t))
    rep = {"file": path, "facets": len(tris), "vertices": len(P), "problems": []}
    probs = rep["problems"]

    def problem(msg):
        if len(probs) < 20:
            probs.append(msg)
        rep["problem_count"] = rep.get("problem_count", 0) + 1

    lo = [min(p[a] for p in P) for a in range(3)]
    hi = [max(p[a] for p in P) for a in range(3)]
    rep["bbox"] = [lo, hi]

    good = []
    for f, t in enumerate(tris):
        if len(set(t)) < 3:
            problem(f"facet {f}: repeated vertex")
        elif collinear(*(P[i] for i in t)):
            problem(f"facet {f}: zero area (collinear corners)")
        else:
            good.append(f)

    # edges
    directed = defaultdict(list)
    for f, t in enumerate(tris):
        for k in range(3):
            directed[(t[k], t[(k + 1) % 3])].append(f)
    undirected = defaultdict(int)
    for (u, v), fs in directed.items():
        undirected[(min(u, v), max(u, v))] += len(fs)
    for (u, v), n in undirected.items():
        if n != 2:
            problem(f"edge {u}-{v} {P[u]}-{P[v]}: {n} facet(s) (not closed 2-manifold)")
        else:
            if len(directed.get((u, v), [])) != 1 or len(directed.get((v, u), [])) != 1:
                problem(f"edge {u}-{v} {P[u]}: both facets use it in the same direction"
                        " (inconsistent orientation)")
    rep["edges"] = len(undirected)

    # vertex fans: facets around a vertex, connected through their edges at the vertex
    around = defaultdict(list)
    for f, t in enumerate(tris):
        for i in t:
            around[i].append(f)
    bad_fans = 0
    for v, fs in around.items():
        parent = {f: f for f in fs}

        def find(x):
            while parent[x] != x:
                parent[x] = parent[parent[x]]
                x = parent[x]
            return x
        by_edge = defaultdict(list)
        for f in fs:
            for w in tris[f]:
                if w != v:
                    by_edge[w].append(f)
        for w, g in by_edge.items():
            for f in g[1:]:
                parent[find(f)] = find(g[0])
        if len({find(f) for f in fs}) != 1:
            bad_fans += 1
            if bad_fans <= 5:
                problem(f"vertex {v} {P[v]}: facets form several fans (non-manifold vertex)")
    # shells = edge-connected components
    parent = list(range(len(tris)))

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x
    for (u, v), fs in directed.items():
        for f in fs + directed.get((v, u), []):
            parent[find(f)] = find(fs[0])
    comps = defaultdict(list)
    for f in range(len(tris)):
        comps[find(f)].append(f)
    shells = sorted(comps.values(), key=len, reverse=True)
    rep["shells"] = []
    for s in shells:
        vol = math.fsum(_dot(P[tris[f][0]], _cross(P[tris[f][1]], P[tris[f][2]]))
                        for f in s) / 6.0
        vs = {i for f in s for i in tris[f]}
        slo = [min(P[i][a] for i in vs) for a in range(3)]
        shi = [max(P[i][a] for i in vs) for a in range(3)]
        # Euler characteristic -> genus of a closed orientable surface
        es = {(min(a, b), max(a, b)) for f in s for a, b in
              ((tris[f][0], tris[f][1]), (tris[f][1], tris[f][2]), (tris[f][2], tris[f][0]))}
        chi = len(vs) - len(es) + len(s)
        rep["shells"].append({"facets": len(s), "volume": vol, "bbox": [slo, shi],
                              "euler": chi, "genus": (2 - chi) / 2})
        if vol <= 0:
            problem(f"shell with {len(s)} facets: volume {vol} <= 0 (inward or a void)")
    rep["volume"] = math.fsum(s["volume"] for s in rep["shells"])

    # nesting: a vertex of each shell must have winding number 0 w.r.t. every other shell
    if len(shells) > 1 and len(shells) <= 50:
        for a, sa in enumerate(shells):
            x = P[tris[sa[0]][0]]
            for b, sb in enumerate(shells):
                if a == b:
                    continue
                blo, bhi = rep["shells"][b]["bbox"]
                if any(x[k] < blo[k] or x[k] > bhi[k] for k in range(3)):
                    continue
                w = winding(P, [tris[f] for f in sb], x)
                if abs(w) > 0.5:
                    problem(f"shell {a} lies inside shell {b} (winding number {w:.3f})")

    # self-intersections
    if do_intersect and good:
        diag = math.dist(lo, hi)
        avg = math.fsum(math.dist(P[tris[f][0]], P[tris[f][1]]) for f in good) / len(good)
        cell = max(avg * 2, diag * 1e-4)
        gt = [tris[f] for f in good]
        grid = Grid(P, gt, cell)
        boxes = [(tuple(min(P[i][a] for i in t) for a in range(3)),
                  tuple(max(P[i][a] for i in t) for a in range(3))) for t in gt]
        hits = 0
        tested = 0
        for key, members in grid.cells.items():
            for x in range(len(members)):
                i = members[x]
                bi = boxes[i]
                for y in range(x + 1, len(members)):
                    j = members[y]
                    bj = boxes[j]
                    if any(bi[1][a] < bj[0][a] or bj[1][a] < bi[0][a] for a in range(3)):
                        continue
                    # each pair once: in the cell holding the low corner of the box overlap
                    if any(math.floor(max(bi[0][a], bj[0][a]) / cell) != key[a]
                           for a in range(3)):
                        continue
                    tested += 1
                    if tris_intersect(P, gt[i], gt[j]):
                        hits += 1
                        if hits <= 5:
                            problem(f"facets {good[i]} and {good[j]} intersect "
                                    f"(near {P[gt[i][0]]})")
        rep["intersecting_pairs"] = hits
        rep["pairs_tested"] = tested

    # clearance between shells
    if do_clearance and len(shells) > 1:
        rep["clearance"] = clearance(P, tris, shells)
    rep["ok"] = not probs
    return rep


def clearance(P, tris, shells, reach=None):
    """Minimum distance between each pair of shells (vertex-facet and edge-edge), float."""
    out = []
    for a in range(len(shells)):
        for b in range(a + 1, len(shells)):
            best = math.inf
            fa, fb = shells[a], shells[b]
            # candidate cells: grid over shell b's facets
            cell = 10.0
            grid = Grid(P, [tris[f] for f in fb], cell)
            va = sorted({i for f in fa for i in tris[f]})
            ea = sorted({(min(x, y), max(x, y)) for f in fa for x, y in
                         ((tris[f][0], tris[f][1]), (tris[f][1], tris[f][2]),
                          (tris[f][2], tris[f][0]))})
            for r in (1, 2, 4, 8, 16):
                best = math.inf
                for v in va:
                    c = tuple(math.floor(P[v][k] / cell) for k in range(3))
                    cand = set()
                    for i in range(c[0] - r, c[0] + r + 1):
                        for j in range(c[1] - r, c[1] + r + 1):
                            for k in range(c[2] - r, c[2] + r + 1):
                                cand.update(grid.cells.get((i, j, k), ()))
                    for f in cand:
                        t = tris[fb[f]]
                        best = min(best, point_tri_dist(P[v], P[t[0]], P[t[1]], P[t[2]]))
                if best <= r * cell:
                    break
            # the other direction and edge-edge pairs, only near the current best
            gb = Grid(P, [tris[f] for f in fa], cell)
            vb = sorted({i for f in fb for i in tris[f]})
            rr = max(1, math.ceil(best / cell))
            for v in vb:
                c = tuple(math.floor(P[v][k] / cell) for k in range(3))
                for i in range(c[0] - rr, c[0] + rr + 1):
                    for j in range(c[1] - rr, c[1] + rr + 1):
                        for k in range(c[2] - rr, c[2] + rr + 1):
                            for f in gb.cells.get((i, j, k), ()):
                                t = tris[fa[f]]
                                best = min(best, point_tri_dist(P[v], P[t[0]], P[t[1]],
                                                                P[t[2]]))
            eb = {(min(x, y), max(x, y)) for f in fb for x, y in
                  ((tris[f][0], tris[f][1]), (tris[f][1], tris[f][2]),
                   (tris[f][2], tris[f][0]))}
            ecell = defaultdict(list)
            for e in eb:
                m = tuple(math.floor((P[e[0]][k] + P[e[1]][k]) / 2 / cell) for k in range(3))
                ecell[m].append(e)
            half = max(math.dist(P[e[0]], P[e[1]]) for e in eb) / 2
            rr = max(1, math.ceil((best + half + max(math.dist(P[e[0]], P[e[1]])
                                                     for e in ea)) / cell))
            for e in ea:
                m = tuple(math.floor((P[e[0]][k] + P[e[1]][k]) / 2 / cell) for k in range(3))
                for i in range(m[0] - rr, m[0] + rr + 1):
                    for j in range(m[1] - rr, m[1] + rr + 1):
                        for k in range(m[2] - rr, m[2] + rr + 1):
                            for g in ecell.get((i, j, k), ()):
                                best = min(best, seg_seg_dist(P[e[0]], P[e[1]],
                                                              P[g[0]], P[g[1]]))
            out.append({"shells": [a, b], "min_distance": best})
    return out


def main(argv):
    as_json = "--json" in argv
    do_int = "--no-intersect" not in argv
    do_clr = "--clearance" in argv
    files = [a for a in argv if not a.startswith("--")]
    if not files:
        print(__doc__)
        return 2
    status = 0
    reports = []
    for path in files:
        try:
            rep = check(path, do_int, do_clr)
        except (OSError, ValueError, KeyError, IndexError, struct.error) as e:
            print(f"{path}: unreadable: {e}", file=sys.stderr)
            return 2
        reports.append(rep)
        if not rep["ok"]:
            status = 1
        if not as_json:
            print(f"{path}: {rep['facets']} facets, {rep['vertices']} vertices, "
                  f"{len(rep['shells'])} shell(s), volume {rep['volume']:.6g}, "
                  f"bbox {fmt(rep['bbox'])}")
            for k, s in enumerate(rep["shells"]):
                print(f"  shell {k}: {s['facets']} facets, volume {s['volume']:.6g}, "
                      f"genus {s['genus']:g}, bbox {fmt(s['bbox'])}")
            if "intersecting_pairs" in rep:
                print(f"  self-intersection: {rep['intersecting_pairs']} intersecting pairs "
                      f"of {rep['pairs_tested']} candidate pairs tested (exact)")
            for c in rep.get("clearance", []):
                print(f"  clearance shell {c['shells'][0]} <-> {c['shells'][1]}: "
                      f"{c['min_distance']:.3f}")
            for p in rep["problems"]:
                print(f"  PROBLEM: {p}")
            if rep.get("problem_count", 0) > len(rep["problems"]):
                print(f"  ... {rep['problem_count']} problems in all")
            print("  OK: closed, 2-manifold, outward, no self-intersection" if rep["ok"]
                  else "  FAILED")
    if as_json:
        print(json.dumps(reports, indent=1))
    return status


def fmt(b):
    return "[" + ", ".join(f"{x:g}" for x in b[0]) + "] - [" + \
        ", ".join(f"{x:g}" for x in b[1]) + "]"


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
