#!/usr/bin/env bash
# Usage: bash tools/bench/side_by_side_models.sh [OUT_DIR]   (KDMESH=path/to/kdmesh; ~12 min)
# SPDX-License-Identifier: AGPL-3.0-or-later
# One run, side by side, per model (docs/meshing.md): kdmesh end to end, then on its final nodes the kdmesh
# kernel, CGAL insert(range) and TetGen (CLI, no output files). /usr/bin/time -v for each.
set -u
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
K="${KDMESH:-$here/build/kdmesh}"
out="${1:-$here/out/side-by-side}"
mkdir -p "$out" && cd "$out"
for m in gearbox block; do
  if [ $m = gearbox ]; then y=$here/models/gearbox/gearbox-paper.yaml; else y=$here/models/block/block-paper.yaml; fi
  d=$(dirname $y)
  sed -e "s|input: \([a-z]*\).stl|input: $d/\1.stl|" -e "s|      summary: \(.*\)-paper.json|      summary: \1-paper.json\n      nodes: $m.xyz|" $y > $m.yaml
  /usr/bin/time -v $K batch $m.yaml -q > $m-pipe.log 2> $m-pipe.time
  /usr/bin/time -v $K delaunay $m.xyz --json -q > $m-kd.json 2> $m-kd.time
  /usr/bin/time -v $K delaunay $m.xyz --kernel cgal --order cgal --json -q > $m-cgal.json 2> $m-cgal.time
  python3 -c "
import sys
pts=[l.split() for l in open('$m.xyz') if l.strip() and not l.startswith('#')]
with open('$m.node','w') as f:
  f.write('%d 3 0 0\n'%len(pts))
  for i,p in enumerate(pts): f.write('%d %s %s %s\n'%(i,p[0],p[1],p[2]))
"
  /usr/bin/time -v tetgen -zQNEF $m.node > $m-tg.log 2> $m-tg.time
done
echo done > done
