#!/usr/bin/env bash
# kdmesh — the whole pipeline against Gmsh on real parts (issue 22, section 2), side by side:
# each single-body part of models/real/ below is meshed at one uniform size that gives kdmesh
# 1-2M tets, by kdmesh (read to VTU + summary written, every check on) and by Gmsh 4.8
# (gmsh_hxt_geo.sh: ClassifySurfaces 40 deg, CreateGeometry, HXT, the default optimiser,
# General.NumThreads 2; MSH 4.1 written), alternated, RUNS times each. Wall time and peak RSS (KiB) come from
# /usr/bin/time -v; tets and min/max dihedral of both tools from the files they wrote, read by
# tools/bench/verify_tets.py (no kdmesh code). summary.md in OUT_DIR at the end.
# SPDX-License-Identifier: AGPL-3.0-or-later
#
#   bash models/real/fetch.sh; bash tools/bench/pipeline_vs_gmsh.sh [OUT_DIR]   (~5 min)
#
# Environment: KDMESH (default build/kdmesh), PARTS (default below), TETS (the tets aimed
# at, default 1500000), RUNS (default 2).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
K="${KDMESH:-$root/build/kdmesh}"
out="${1:-$root/build/pipeline_vs_gmsh}"
PARTS="${PARTS:-hinge.stl t13_data.stl rotor.ply pinion.ply joint.ply}"
TETS="${TETS:-1500000}"
RUNS="${RUNS:-2}"
PY=/usr/bin/python3
# shellcheck source=tools/bench/gmsh_hxt_geo.sh
source "$root/tools/bench/gmsh_hxt_geo.sh"
command -v gmsh >/dev/null || { echo "pipeline_vs_gmsh: gmsh missing (apt-get install gmsh)" >&2; exit 2; }
mkdir -p "$out"
rm -f "$out/runs.csv"
tets_of() {  # the size whose kdmesh mesh has ~TETS tets: one run at diag/30, scaled by h^3
  "$PY" - "$@" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
print('%.6g' % (float(sys.argv[2]) * (s['counts']['tets'] / float(sys.argv[3])) ** (1 / 3)))
PY
}
for part in $PARTS; do
  src="$root/models/real/$part"
  [ -f "$src" ] || { echo "pipeline_vs_gmsh: $src missing (bash models/real/fetch.sh)" >&2; exit 2; }
  d="$out/${part%.*}"
  mkdir -p "$d"
  diag=$(grep "^$part," "$root/docs/real_parts/corpus.csv" | cut -d, -f6)
  h0=$("$PY" -c "print('%.6g' % ($diag / 30))")
  "$K" mesh "$src" --size "$h0" -o "$d/calib.vtu" --summary "$d/calib.json" -q >/dev/null
  h=$(tets_of "$d/calib.json" "$h0" "$TETS")
  "$K" mesh "$src" --size "$h" -o "$d/calib.vtu" --summary "$d/calib.json" -q >/dev/null  # again: refinement is not h^3
  h=$(tets_of "$d/calib.json" "$h" "$TETS")
  rm -f "$d/calib.vtu"
  gmsh_hxt_geo "$src" "$h" >"$d/in.geo"
  for r in $(seq 1 "$RUNS"); do
    /usr/bin/time -v -o "$d/kdmesh-$r.time" "$K" mesh "$src" --size "$h" -o "$d/kdmesh.vtu" \
      --summary "$d/kdmesh-$r.json" -q >/dev/null 2>"$d/kdmesh-$r.err"
    /usr/bin/time -v -o "$d/gmsh-$r.time" gmsh "$d/in.geo" -3 -format msh4 -o "$d/gmsh.msh" >"$d/gmsh-$r.log" 2>&1
    for tool in kdmesh gmsh; do
      mesh="$d/kdmesh.vtu"; [ "$tool" = gmsh ] && mesh="$d/gmsh.msh"
      "$PY" - "$root/tools/bench" "$mesh" "$d/$tool-$r.time" "$part" "$h" "$tool" "$r" >>"$out/runs.csv" <<'PY'
import re, sys
sys.path.insert(0, sys.argv[1])
import verify_tets as v
pts, tets = v.read_tets(sys.argv[2])
d = v.dihedral_angles(pts, tets)
t = open(sys.argv[3]).read()
wall = sum(float(x) * 60 ** i for i, x in enumerate(reversed(re.search(r'Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)', t).group(1).split(':'))))
rss = int(re.search(r'Maximum resident set size \(kbytes\): (\d+)', t).group(1))
print('%s,%s,%s,%s,%.2f,%d,%d,%.2f,%.1f' % (sys.argv[4], sys.argv[5], sys.argv[6], sys.argv[7], wall, rss, len(tets), d.min(), d.max()))
PY
    done
    rm -f "$d/kdmesh.vtu" "$d/gmsh.msh"
  done
done
"$PY" - "$out/runs.csv" >"$out/summary.md" <<'PY'
import collections, statistics, sys
rows = [l.strip().split(',') for l in open(sys.argv[1]) if l.strip()]
by = collections.defaultdict(list)
for part, h, tool, r, wall, rss, tets, dmin, dmax in rows:
    by[(part, h, tool)].append((float(wall), int(rss), int(tets), float(dmin), float(dmax)))
print('| part | h | tool | tets | wall (s), each run | tets/s (median) | peak RSS (KiB) | min / max dihedral |')
print('|---|---|---|---|---|---|---|---|')
ratios = []
for part in dict.fromkeys(k[0] for k in by):
    rate = {}
    for tool in ['kdmesh', 'gmsh']:
        runs = by[(part, next(k[1] for k in by if k[0] == part), tool)]
        h = next(k[1] for k in by if k[0] == part)
        walls = [x[0] for x in runs]
        rate[tool] = statistics.median(x[2] / x[0] for x in runs)
        print('| %s | %s | %s | %d | %s | %.0f | %d | %.2f / %.1f |' % (part, h, tool, runs[0][2], ', '.join('%.2f' % w for w in walls),
              rate[tool], max(x[1] for x in runs), min(x[3] for x in runs), max(x[4] for x in runs)))
    ratios.append(rate['kdmesh'] / rate['gmsh'])
    print('| | | **kdmesh / Gmsh tets/s** | | | **%.2f** | | |' % ratios[-1])
print('\nMedian over the parts of kdmesh / Gmsh tets per second: %.2f' % statistics.median(ratios))
PY
cat "$out/summary.md"
