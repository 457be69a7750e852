#!/usr/bin/env bash
# kdmesh — real-part benchmark (issue 18, item 5): meshes every valid part of models/real/ at
# h = diag/20, diag/40, diag/80 with kdmesh, TetGen, Gmsh and CGAL Mesh_3, checks every mesh
# with tools/bench/verify_tets.py (independent of kdmesh), and writes docs/real_parts.md.
# SPDX-License-Identifier: AGPL-3.0-or-later
#
#   bash models/real/fetch.sh                       (once: the parts)
#   bash tools/bench/real_parts.sh                  all tools, all parts, all sizes, then the report
#   TOOLS=kdmesh KDMESH=/path/to/kdmesh bash tools/bench/real_parts.sh
#                                                   re-run one tool: only its rows are replaced
#   bash tools/bench/real_parts.sh report           the report alone, from the CSV
#
# Environment:
#   TOOLS     tools to run, of "kdmesh tetgen gmsh mesh3" (default: all four)
#   PARTS     part file names in models/real/ (default: every part fetch.sh marks "bench")
#   SIZES     divisors of the bbox diagonal (default: "20 40 80")
#   KDMESH    kdmesh executable (default: build/kdmesh)
#   KDMESH_VERSION  the version column of kdmesh's rows (default: the last commit that
#             changed the mesher's sources in the executable's own work tree; for a copy
#             outside one, the repository's HEAD, which need not be what it was built from)
#   MESH3     CGAL Mesh_3 executable (default: built on demand in $WORK/build-mesh3 with
#             -DKDMESH_BENCH_MESH3=ON, -j$JOBS; the compile takes minutes)
#   TIMEOUT   seconds per mesher run (default 300; a timeout is a failure, reported as such)
#   VTIMEOUT  seconds per verification (default 600)
#   RESULTS   the CSV of all cases, one row per (tool, part, size); rows of the tools run are
#             replaced as each case ends (default docs/real_parts/results.csv)
#   WORK      scratch directory: meshes, logs, per-case JSON (default build/real_parts)
#   KEEP=1    keep the meshes (default: deleted once verified)
#   REPORT=0  skip writing docs/real_parts.md at the end
# Each mesher runs under `timeout` and /usr/bin/time -v (wall time, peak RSS in KiB).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
bench="$root/tools/bench"
# shellcheck source=tools/bench/gmsh_hxt_geo.sh
source "$bench/gmsh_hxt_geo.sh"
TOOLS="${TOOLS:-kdmesh tetgen gmsh mesh3}"
SIZES="${SIZES:-20 40 80}"
KDMESH="${KDMESH:-$root/build/kdmesh}"
TIMEOUT="${TIMEOUT:-300}"
VTIMEOUT="${VTIMEOUT:-600}"
RESULTS="${RESULTS:-$root/docs/real_parts/results.csv}"
WORK="${WORK:-$root/build/real_parts}"
MESH3="${MESH3:-$WORK/build-mesh3/mesh3_part}"
KEEP="${KEEP:-0}"
REPORT="${REPORT:-1}"
JOBS="${JOBS:-1}"
PY=/usr/bin/python3  # Debian's python3 with python3-numpy, -scipy, -meshio (tools/setup.sh)
CORPUS="$root/docs/real_parts/corpus.csv"
MD="$root/docs/real_parts.md"

report() {
  "$PY" "$bench/real_parts_report.py" report --results "$RESULTS" --corpus "$CORPUS" --out "$MD"
  echo "real_parts: wrote $MD"
}
if [ "${1:-}" = "report" ]; then
  report
  exit 0
fi

for t in $TOOLS; do
  case "$t" in kdmesh|tetgen|gmsh|mesh3) ;; *) echo "real_parts: unknown tool '$t'" >&2; exit 2 ;; esac
done
for exe in /usr/bin/time timeout; do
  command -v "$exe" >/dev/null || { echo "real_parts: $exe missing (apt-get install time coreutils)" >&2; exit 2; }
done
"$PY" -c 'import numpy, scipy, meshio' 2>/dev/null ||
  { echo "real_parts: $PY needs numpy, scipy, meshio (apt-get install python3-numpy python3-scipy python3-meshio)" >&2; exit 2; }

# the parts: fetch.sh --list prints "out<TAB>package<TAB>path<TAB>flag"
declare -A PKG SRC FLAG
all=()
while IFS=$'\t' read -r out pkg path flag; do
  PKG[$out]="$pkg"; SRC[$out]="$path"; FLAG[$out]="$flag"
  all+=("$out")
done < <(bash "$root/models/real/fetch.sh" --list)
if [ -n "${PARTS:-}" ]; then
  read -r -a parts <<<"$PARTS"
else
  parts=()
  for p in "${all[@]}"; do [ "${FLAG[$p]}" = bench ] && parts+=("$p"); done
fi
for p in "${parts[@]}"; do
  [ -n "${PKG[$p]:-}" ] || { echo "real_parts: '$p' is not in models/real/fetch.sh" >&2; exit 2; }
  [ -f "$root/models/real/$p" ] || { echo "real_parts: models/real/$p missing: run bash models/real/fetch.sh" >&2; exit 2; }
done

mkdir -p "$WORK/facts" "$WORK/cases" "$(dirname "$RESULTS")" "$(dirname "$CORPUS")"

# per part: facets, bbox diagonal, volume, sharpest input dihedral (cached by content hash)
for p in "${all[@]}"; do
  f="$root/models/real/$p"
  [ -f "$f" ] || continue
  sum=$(sha256sum "$f" | cut -c1-16)
  j="$WORK/facts/$p.$sum.json"
  [ -s "$j" ] || "$PY" "$bench/verify_tets.py" --surface "$f" --json "$j" >/dev/null
  ln -sf "$(basename "$j")" "$WORK/facts/$p.json"
done
corpus_args=()
for p in "${all[@]}"; do
  [ -f "$WORK/facts/$p.json" ] || continue
  corpus_args+=("$p|${PKG[$p]}|${SRC[$p]}|${FLAG[$p]}|$WORK/facts/$p.json")
done
"$PY" "$bench/real_parts_report.py" corpus --out "$CORPUS" "${corpus_args[@]}"

if [[ " $TOOLS " == *" kdmesh "* ]]; then
  [ -x "$KDMESH" ] || { echo "real_parts: KDMESH=$KDMESH is not an executable (build it first)" >&2; exit 2; }
  KDMESH="$(cd "$(dirname "$KDMESH")" && pwd)/$(basename "$KDMESH")"
fi
if [[ " $TOOLS " == *" mesh3 "* ]] && [ ! -x "$MESH3" ]; then
  echo "real_parts: building $MESH3 (CGAL Mesh_3; minutes)"
  launcher=()
  command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  cmake -S "$root" -B "$WORK/build-mesh3" -DCMAKE_BUILD_TYPE=Release -DKDMESH_TESTS=OFF \
    -DKDMESH_BENCH_MESH3=ON "${launcher[@]}" >/dev/null
  cmake --build "$WORK/build-mesh3" --target mesh3_part -j "$JOBS" >/dev/null
  MESH3="$WORK/build-mesh3/mesh3_part"
fi
if [[ " $TOOLS " == *" tetgen "* ]]; then command -v tetgen >/dev/null || { echo "real_parts: tetgen missing" >&2; exit 2; }; fi
if [[ " $TOOLS " == *" gmsh "* ]]; then command -v gmsh >/dev/null || { echo "real_parts: gmsh missing" >&2; exit 2; }; fi

version() {
  case "$1" in
    kdmesh) echo "kdmesh $(cd "$root" && git rev-parse --short HEAD 2>/dev/null || echo ?) $(basename "$(dirname "$(dirname "$KDMESH")")")/$(basename "$(dirname "$KDMESH")")" ;;
    tetgen) echo "tetgen $(dpkg-query -W -f='${Version}' tetgen 2>/dev/null || echo ?)" ;;
    gmsh) echo "gmsh $(gmsh --version 2>&1 | tail -1)" ;;
    mesh3) echo "CGAL $(dpkg-query -W -f='${Version}' libcgal-dev 2>/dev/null || echo ?) Mesh_3" ;;
  esac
}
declare -A VERSION
for t in $TOOLS; do VERSION[$t]="$(version "$t")"; done
if [[ " $TOOLS " == *" kdmesh "* ]]; then
  # the last commit that changed the mesher's sources in the executable's own tree (when the
  # executable sits in BUILD_DIR/ of a git work tree), and whether they have uncommitted changes
  kd_src="$(cd "$(dirname "$KDMESH")/.." && git log -1 --format=%h -- core io mesher sizing tools/kdmesh tools/app 2>/dev/null || true)"
  if [ -n "$kd_src" ]; then
    dirty="$(cd "$(dirname "$KDMESH")/.." && git status --porcelain -- core io mesher sizing tools/kdmesh tools/app 2>/dev/null | head -1)"
    VERSION[kdmesh]="kdmesh sources at $kd_src${dirty:+ + uncommitted changes} ($KDMESH)"
  fi
  if [ -n "${KDMESH_VERSION:-}" ]; then VERSION[kdmesh]="$KDMESH_VERSION"; fi
fi

run_case() {  # tool part div
  local tool="$1" part="$2" div="$3"
  local src="$root/models/real/$part" d="$WORK/cases/$tool/$part/$div"
  rm -rf "$d"; mkdir -p "$d"
  local h
  h=$("$PY" -c "import json,sys; print(repr(json.load(open(sys.argv[1]))['bbox_diag'] / $div))" "$WORK/facts/$part.json")
  local mesh="" cmd=()
  case "$tool" in
    kdmesh)
      mesh="$d/out.vtu"
      cmd=("$KDMESH" mesh "$src" --size "$h" -o "$mesh" --summary "$d/summary.json") ;;
    tetgen)
      local ext="${part##*.}" v
      if [ "$ext" = stl ] && "$PY" -c 'import os, struct, sys
d = open(sys.argv[1], "rb").read(84)
sys.exit(len(d) != 84 or 84 + 50 * struct.unpack("<I", d[80:])[0] != os.path.getsize(sys.argv[1]))' "$src"; then
        # a binary STL (lever.stl's header starts with "solid"): TetGen would read it as ASCII
        # ("Wrong number of vertices"), so it gets the same triangles as exact ASCII PLY
        "$PY" "$bench/verify_tets.py" --to-ply "$src" "$d/in.ply"
        ext=ply
      else
        cp "$src" "$d/in.$ext"
      fi
      v=$("$PY" -c "import math; print('%.6g' % ($h**3 / (6*math.sqrt(2))))")
      mesh="$d/in.1.ele"
      # unbuffered: TetGen aborts (uncaught int) after printing its error to stdout
      cmd=(stdbuf -o0 tetgen -pq1.414a"$v"Q "$d/in.$ext") ;;
    gmsh)
      mesh="$d/out.msh"
      gmsh_hxt_geo "$src" "$h" >"$d/in.geo"
      cmd=(gmsh "$d/in.geo" -3 -format msh4 -o "$mesh") ;;
    mesh3)
      mesh="$d/out.mesh"
      cmd=("$MESH3" "$src" "$h" "$mesh") ;;
  esac
  local rc=0
  /usr/bin/time -v -o "$d/time.txt" timeout -k 10 "$TIMEOUT" "${cmd[@]}" >"$d/stdout.txt" 2>"$d/stderr.txt" || rc=$?
  local vrc=-
  if [ "$rc" -eq 0 ] && [ -s "$mesh" ]; then
    vrc=0
    timeout -k 10 "$VTIMEOUT" "$PY" "$bench/verify_tets.py" "$mesh" "$src" "$h" --json "$d/verify.json" >/dev/null 2>"$d/verify_stderr.txt" || vrc=$?
  fi
  flock "$WORK/results.lock" "$PY" "$bench/real_parts_report.py" add --results "$RESULTS" --tool "$tool" --part "$part" \
    --div "$div" --h "$h" --rc "$rc" --vrc "$vrc" --timeout "$TIMEOUT" --dir "$d" \
    --version "${VERSION[$tool]}" --cmd "${cmd[*]}"
  [ "$KEEP" = 1 ] || rm -f "$d"/*.vtu "$d"/*.msh "$d"/*.mesh "$d"/*.ele "$d"/*.node "$d"/*.face \
    "$d"/*.edge "$d"/*.stl "$d"/*.ply
}

start=$(date +%s)
n=0
for part in "${parts[@]}"; do
  for div in $SIZES; do
    for tool in $TOOLS; do
      run_case "$tool" "$part" "$div"
      n=$((n + 1))
    done
  done
done
echo "real_parts: $n cases in $(( $(date +%s) - start )) s; results in $RESULTS"
[ "$REPORT" = 0 ] || report
