#!/usr/bin/env python3
# kdmesh — the layering of the sources, enforced (ctest `layering`): every `#include "..."` of
# a project file must name a unit its own unit may use. The units are the top-level folders
# (core, io, sizing), the pipeline's stage folders under mesher/, and the tools' libraries.
# Each stage sees only the stages before it, io and sizing never see the mesher, and the
# mesher never sees io (the front door has no side effects). A new folder must be added here.
# SPDX-License-Identifier: AGPL-3.0-or-later
#
#   python3 tests/layering.py [ROOT]      exit 0 if clean, 1 with one line per violation
#   python3 tests/layering.py --self-test plants violations in a scratch tree, expects each found
import pathlib
import re
import sys
import tempfile

# mesher/'s top-level files: shared ground every stage may use, the domain bundle, and the
# front door over all stages.
MESHER_TOP = {
    "node_set": "mesher/base", "bucket_scatter": "mesher/base", "distinct_sorter": "mesher/base",
    "worker_team": "mesher/base", "tet_quality": "mesher/base", "point_values": "mesher/base",
    "domain": "mesher/domain",
    "mesh_solid": "mesher/front", "resource_estimate": "mesher/front",
    "numeric_ranges": "mesher/front",
}

# unit -> the units it may include (besides itself). Listed in pipeline order.
BASE = ["core", "mesher/base"]
ALLOWED = {
    "core": [],
    "io": ["core"],
    "sizing": ["core"],
    "mesher/base": ["core"],
    "mesher/delaunay": BASE,
    "mesher/order": BASE,
    "mesher/reference": BASE + ["mesher/delaunay", "mesher/order"],
    "mesher/surface": BASE + ["sizing", "mesher/delaunay"],
    "mesher/domain": BASE + ["sizing", "mesher/surface"],
    "mesher/placement": BASE + ["sizing", "mesher/delaunay", "mesher/surface", "mesher/domain"],
    "mesher/volume": BASE + ["sizing", "mesher/delaunay", "mesher/order", "mesher/surface",
                             "mesher/domain"],
    "mesher/quality": BASE + ["sizing", "mesher/delaunay", "mesher/surface", "mesher/domain",
                              "mesher/volume"],
    "mesher/improve": BASE + ["sizing", "mesher/delaunay", "mesher/surface", "mesher/domain",
                              "mesher/volume", "mesher/quality"],
    "mesher/fe": BASE + ["sizing", "mesher/delaunay", "mesher/surface", "mesher/domain",
                         "mesher/placement", "mesher/volume"],
}
MESHER = sorted(u for u in ALLOWED if u.startswith("mesher/")) + ["mesher/front"]
ALLOWED["mesher/front"] = ["core", "sizing"] + MESHER
# The tools: the application layer (which the Python module links alone) sees no benchmark or
# comparison code; the benchmark library sees no application code.
ALLOWED["tools/app"] = ["core", "io", "sizing"] + MESHER
ALLOWED["tools/bench/lib"] = ["core", "sizing"] + MESHER
ALLOWED["tools/compare"] = ALLOWED["tools/app"] + ["tools/app"]
ALLOWED["tools/python"] = ALLOWED["tools/app"] + ["tools/app"]
ALLOWED["tools/bench"] = ALLOWED["tools/app"] + ["tools/app", "tools/bench/lib"]
ALLOWED["tools/kdmesh"] = ALLOWED["tools/app"] + ["tools/app", "tools/bench/lib", "tools/compare"]


def unit_of(rel):
    """The unit of a path relative to the root, or None if it is in none (tests, fuzz)."""
    parts = pathlib.PurePosixPath(rel).parts
    if not parts:
        return None
    if parts[0] in ("core", "io", "sizing"):
        return parts[0]
    if parts[0] == "mesher":
        if len(parts) == 2:
            return MESHER_TOP.get(pathlib.PurePosixPath(parts[1]).stem, "mesher/?" + parts[1])
        return "mesher/" + parts[1]
    if parts[0] == "tools" and len(parts) > 2:
        if parts[1] == "bench" and parts[2] == "lib":
            return "tools/bench/lib"
        return "tools/" + parts[1]
    return None


def violations(root):
    out = []
    folders = ["core", "io", "sizing", "mesher", "tools"]
    for folder in folders:
        for f in sorted((root / folder).rglob("*")):
            if f.suffix not in (".h", ".cpp") or not f.is_file():
                continue
            rel = f.relative_to(root).as_posix()
            unit = unit_of(rel)
            if unit is None:
                continue
            if unit not in ALLOWED:
                out.append(f"{rel}: unit {unit} is not in tests/layering.py's table")
                continue
            text = f.read_text(encoding="utf-8", errors="replace")
            for n, line in enumerate(text.splitlines(), 1):
                m = re.match(r'\s*#\s*include\s+"([^"]+)"', line)
                if not m:
                    continue
                target = unit_of(m.group(1))
                if target is None or target == unit:
                    continue  # a third-party or generated header, or the unit's own
                if target not in ALLOWED[unit]:
                    out.append(f"{rel}:{n}: {unit} includes {m.group(1)} ({target}), "
                               f"which it may not use")
    return out


def self_test():
    """Plants one violation of each kind in a scratch tree and expects exactly those."""
    files = {
        "core/a.h": '#include "io/b.h"\n',                          # core sees nothing
        "io/b.h": '#include "core/a.h"\n',                          # fine
        "sizing/c.h": '#include "mesher/node_set.h"\n',             # sizing never sees the mesher
        "mesher/node_set.h": '#include "core/a.h"\n',               # fine
        "mesher/delaunay/d.h": '#  include "mesher/volume/e.h"\n',  # a stage sees only earlier ones
        "mesher/volume/e.h": '#include "mesher/delaunay/d.h"\n#include <vector>\n',  # fine
        "mesher/volume/f.cpp": '#include "io/b.h"\n',               # the mesher never sees io
        "mesher/newstage/g.h": '#include "core/a.h"\n',             # a folder not in the table
        "tools/app/h.cpp": '#include "tools/compare/i.h"\n',        # app sees no comparison code
    }
    with tempfile.TemporaryDirectory() as d:
        root = pathlib.Path(d)
        for rel, text in files.items():
            (root / rel).parent.mkdir(parents=True, exist_ok=True)
            (root / rel).write_text(text)
        found = sorted(v.split(":")[0] for v in violations(root))
    want = sorted(["core/a.h", "sizing/c.h", "mesher/delaunay/d.h", "mesher/volume/f.cpp",
                   "mesher/newstage/g.h", "tools/app/h.cpp"])
    if found != want:
        print(f"layering self-test: found violations in {found}, expected {want}")
        return 1
    print(f"layering self-test: the {len(want)} planted violations found, nothing else")
    return 0


def main():
    if sys.argv[1:] == ["--self-test"]:
        return self_test()
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else
                        pathlib.Path(__file__).resolve().parent.parent)
    bad = violations(root)
    for line in bad:
        print(line)
    units = {unit_of(p.relative_to(root).as_posix()) for p in (root / "mesher").rglob("*.h")}
    print(f"layering: {len(bad)} violation(s); {len(units)} mesher units checked")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
