#!/usr/bin/env python3
# kdmesh — converts an OFF surface to ASCII PLY, keeping every number's text unchanged.
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Usage: off_to_ply.py IN.off OUT.ply

kdmesh reads STL and PLY, CGAL's sample meshes are OFF. This copies the vertex coordinates
as the same decimal strings (no floating-point round trip) and the faces as the same index
lists, into an ASCII PLY with `element vertex` (x y z, double) and `element face`
(vertex_indices). Comments (#) and per-face colours after the index list are dropped.
OUT is written atomically (temporary file + rename). Exit 1 on a malformed OFF, naming the
line.
"""
import os
import sys


def main(argv):
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    src, dst = argv
    lines = []
    with open(src) as f:
        for no, line in enumerate(f, 1):
            t = line.split("#", 1)[0].split()
            if t:
                lines.append((no, t))
    try:
        no, head = lines[0]
        if head[0] != "OFF":
            raise ValueError(f"{src}:{no}: expected 'OFF', found {head[0]!r}")
        rest = head[1:] or lines.pop(1)[1]
        nv, nf = int(rest[0]), int(rest[1])
        body = lines[1:]
        if len(body) < nv + nf:
            raise ValueError(f"{src}: {len(body)} data lines, header says {nv} + {nf}")
        verts = []
        for no, t in body[:nv]:
            if len(t) < 3:
                raise ValueError(f"{src}:{no}: vertex with {len(t)} coordinates")
            [float(x) for x in t[:3]]  # validates
            verts.append(" ".join(t[:3]))
        faces = []
        for no, t in body[nv:nv + nf]:
            k = int(t[0])
            idx = t[1:1 + k]
            if k < 3 or len(idx) != k or any(not 0 <= int(i) < nv for i in idx):
                raise ValueError(f"{src}:{no}: bad face {' '.join(t)}")
            faces.append(f"{k} " + " ".join(idx))
    except (ValueError, IndexError) as e:
        print(f"off_to_ply: {e}", file=sys.stderr)
        return 1
    tmp = f"{dst}.tmp-{os.getpid()}"
    with open(tmp, "w") as f:
        f.write("ply\nformat ascii 1.0\n")
        f.write(f"comment converted from {os.path.basename(src)}"
                " by kdmesh models/real/off_to_ply.py\n")
        f.write(f"element vertex {nv}\nproperty double x\nproperty double y\nproperty double z\n")
        f.write(f"element face {nf}\nproperty list uchar int vertex_indices\nend_header\n")
        f.write("\n".join(verts) + "\n")
        f.write("\n".join(faces) + "\n")
    os.replace(tmp, dst)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
