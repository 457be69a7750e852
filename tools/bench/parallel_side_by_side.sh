#!/usr/bin/env bash
# Usage: bash tools/bench/parallel_side_by_side.sh [OUT_DIR] [N]   (KDMESH=path/to/kdmesh; ~7 min)
#        DISTS="cube axes" (default) or any of the seven distributions; REPS=3 (default)
# SPDX-License-Identifier: AGPL-3.0-or-later
# The kdmesh kernel with its default order (kd-bfs-hilbert) sequential (t1) and on two threads
# (t2), and with the paper's kd-bfs order sequential (kd-bfs), against CGAL 5.5's insert(range)
# twice: stock (a plain Delaunay_triangulation_3<Epick> inserting a Point_3 range, --kernel
# cgal-plain) and with point ids as vertex info (--kernel cgal). N (default 1M) points of each
# distribution in DISTS from `kdmesh points --seed 1`. Separate processes, alternated REPS
# times so that the machine's drift hits every column alike; each under /usr/bin/time -v.
# Times are order + Delaunay as `kdmesh delaunay` reports them (CGAL: its insert(range), which
# sorts internally). pair-a and pair-b are two sequential runs started together, one per core:
# each one's slowdown against t1 bounds what a second thread can give. Writes summary.md (one
# row per process, then each ratio per alternation and its median) to OUT_DIR.
set -eu
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
K="$(realpath "${KDMESH:-$here/build/kdmesh}")"  # absolute: the runs cd to OUT_DIR
out="${1:-$here/out/parallel-side-by-side}"
n="${2:-1000000}"
dists="${DISTS:-cube axes}"
reps="${REPS:-3}"
mkdir -p "$out" && cd "$out"
echo "| points | kernel | rep | order + Delaunay (s) | peak RSS (kB) | orient/pt | conflicts/pt | rounds | deferrals |" > summary.md
echo "|---|---|---|---|---|---|---|---|---|" >> summary.md
for d in $dists; do
  [ -f $d.xyz ] || $K points --dist $d -n "$n" --seed 1 -o $d.xyz -q
  for rep in $(seq 1 "$reps"); do
    for mode in t1 t2 kd-bfs stock cgal pair-a; do
      case $mode in
        t1) args=(--threads 1);;
        t2) args=(--threads 2);;
        kd-bfs) args=(--threads 1 --order kd-bfs);;
        stock) args=(--kernel cgal-plain --order cgal);;
        cgal) args=(--kernel cgal --order cgal);;
        pair-a) args=(--threads 1);;
      esac
      if [ "$mode" = pair-a ]; then
        # Two sequential runs at once, one per core: how much the cores slow each other down
        # (shared cache and memory), the ceiling of the two-thread speed-up.
        /usr/bin/time -v $K delaunay $d.xyz "${args[@]}" --json -q > $d-pair-b-$rep.json 2> $d-pair-b-$rep.time &
        /usr/bin/time -v $K delaunay $d.xyz "${args[@]}" --json -q > $d-$mode-$rep.json 2> $d-$mode-$rep.time
        wait
      else
        /usr/bin/time -v $K delaunay $d.xyz "${args[@]}" --json -q > $d-$mode-$rep.json 2> $d-$mode-$rep.time
      fi
      for m in $mode $([ "$mode" = pair-a ] && echo pair-b); do
      python3 - "$d" "$m" "$rep" >> summary.md <<'PY'
import json, re, sys
d, mode, rep = sys.argv[1:4]
j = json.load(open(f"{d}-{mode}-{rep}.json"))
rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", open(f"{d}-{mode}-{rep}.time").read()).group(1)
c = j.get("counts", {})
sec = j["seconds"]
total = sec["order"] + sec["delaunay"]
f = lambda k: ("%.2f" % c[k]) if k in c else ""
print(f"| {j['points']} {d} | {mode} | {rep} | {total:.3f} | {rss} | {f('orient_tests_per_point')} | "
      f"{f('conflicts_per_point')} | {c.get('parallel_rounds', '')} | {c.get('deferrals', '')} |")
PY
      done
    done
  done
done
# Per distribution, the ratios of each alternation and their medians: one thread against stock
# CGAL, two threads against one, and the pair bound (twice the one-thread time over the slower
# of the pair: what a second core gave two independent runs on this machine).
python3 - >> summary.md <<'PY'
import statistics
rows = [l.split("|") for l in open("summary.md") if l.startswith("| ") and l.split("|")[3].strip().isdigit()]
t = {}
for r in rows:
    t.setdefault(r[1].strip(), {}).setdefault(r[2].strip(), {})[int(r[3])] = float(r[4])
print()
print("| points | ratio | per alternation | median |")
print("|---|---|---|---|")
for dist, m in t.items():
    reps = sorted(m["t1"])
    ratios = {
        "t1 / stock": [m["t1"][i] / m["stock"][i] for i in reps],
        "t1 / t2": [m["t1"][i] / m["t2"][i] for i in reps],
        "pair bound": [2 * m["t1"][i] / max(m["pair-a"][i], m["pair-b"][i]) for i in reps],
    }
    for name, v in ratios.items():
        print(f"| {dist} | {name} | {', '.join('%.3f' % x for x in v)} | {statistics.median(v):.3f} |")
PY
cat summary.md
