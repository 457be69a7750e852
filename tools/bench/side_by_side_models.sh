#!/usr/bin/env bash
# Usage: bash tools/bench/side_by_side_models.sh [OUT_DIR]   (KDMESH=path/to/kdmesh; ~20 min)
# SPDX-License-Identifier: AGPL-3.0-or-later
# One run, side by side, per paper-size model (docs/meshing.md, and Tables 16-17 of
# docs/bench/README.md): kdmesh end to end, then on its final nodes the kdmesh kernel with the
# kd-bfs, hilbert and brio orders, CGAL insert(range) (timed, then counted with counting
# traits) and TetGen (CLI, no output files). /usr/bin/time -v for each; summary.md at the end.
# The random order is not run: on graded node sets it needs thousands of orientation tests
# per point without a locate structure (the paper's Table 16 aborted it too).
set -u
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
K="${KDMESH:-$here/build/kdmesh}"
out="${1:-$here/out/side-by-side}"
mkdir -p "$out" && cd "$out"
for m in gearbox block; do
  y=$here/models/$m/$m-paper.yaml
  d=$(dirname $y)
  sed -e "s|input: \([a-z_]*\).stl|input: $d/\1.stl|g" -e "s|      summary: \(.*\)-paper.json|      summary: \1-paper.json\n      nodes: $m.xyz|" $y > $m.yaml
  /usr/bin/time -v $K batch $m.yaml -q > $m-pipe.log 2> $m-pipe.time
  for o in kd-bfs hilbert brio; do
    /usr/bin/time -v $K delaunay $m.xyz --order $o --json -q > $m-kd-$o.json 2> $m-kd-$o.time
  done
  /usr/bin/time -v $K delaunay $m.xyz --kernel cgal --order cgal --json -q > $m-cgal.json 2> $m-cgal.time
  $K delaunay $m.xyz --kernel cgal --order cgal --count --json -q > $m-cgal-count.json 2> /dev/null
  python3 -c "
pts=[l.split() for l in open('$m.xyz') if l.strip() and not l.startswith('#')]
with open('$m.node','w') as f:
  f.write('%d 3 0 0\n'%len(pts))
  for i,p in enumerate(pts): f.write('%d %s %s %s\n'%(i,p[0],p[1],p[2]))
"
  /usr/bin/time -v tetgen -zQNEF $m.node > $m-tg.log 2> $m-tg.time
  rm -f $m.node
done
python3 - <<'PY' > summary.md
import json, re
def rss(f):
    return int(re.search(r'Maximum resident set size \(kbytes\): (\d+)', open(f).read()).group(1)) * 1024
def wall(f):
    t = re.search(r'Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)', open(f).read()).group(1).split(':')
    return sum(float(x) * 60 ** i for i, x in enumerate(reversed(t)))
print('| model | run | order + Delaunay (s) | orient. / pt | conflicts / pt | peak RSS | bytes / pt |')
print('|---|---|---|---|---|---|---|')
for m in ['gearbox', 'block']:
    rows = [('kdmesh ' + o, 'kd-' + o) for o in ['kd-bfs', 'hilbert', 'brio']] + [('CGAL insert(range)', 'cgal')]
    for name, tag in rows:
        j = json.load(open('%s-%s.json' % (m, tag)))
        n = j['counts']['inserted']
        c = j['counts'] if tag != 'cgal' else json.load(open('%s-cgal-count.json' % m))['counts']
        s = j['seconds']['order'] + j['seconds']['delaunay']
        r = rss('%s-%s.time' % (m, tag))
        print('| %s %d | %s | %.2f | %.2f | %.2f | %.0f MB | %.0f |' % (m, n, name, s, c['orient_tests_per_point'], c['conflicts_per_point'], r / 1e6, r / n))
    print('| %s | TetGen CLI (wall, with reading) | %.2f | | | %.0f MB | |' % (m, wall('%s-tg.time' % m), rss('%s-tg.time' % m) / 1e6))
PY
echo done > done
