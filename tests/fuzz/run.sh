#!/usr/bin/env bash
# kdmesh fuzzing — build every libFuzzer target with clang (ASan + UBSan) and run each one.
#   bash tests/fuzz/run.sh [SECONDS_PER_TARGET=60] [TARGET ...]
# Builds into build-fuzz/, runs on a scratch copy of the committed seed corpus
# (tests/fuzz/corpus/<target>/), so new inputs never dirty the repository. Any crash,
# sanitizer report, untyped exception, hang (>10 s per input) or allocation over 512 MB is a
# finding: the reproducer is saved to build-fuzz/findings/<target>/ and the script exits 1.
# Longer runs: the same command with more seconds (docs/robustness.md).
# SPDX-License-Identifier: AGPL-3.0-or-later
set -euo pipefail
cd "$(dirname "$0")/../.."
SECONDS_PER_TARGET="${1:-60}"
shift || true
OUT=build-fuzz
mkdir -p "$OUT"
CXX="${FUZZ_CXX:-clang++}"
JOBS="${JOBS:-$(nproc)}"
# Objects are instrumented for the fuzzer (coverage) without its main(); the link adds it.
FLAGS=(-std=c++20 -O1 -g -fno-omit-frame-pointer -fsanitize=fuzzer-no-link,address,undefined
       -fno-sanitize-recover=undefined -I. -DKDMESH_FUZZ)
LINK_FLAGS=(-fsanitize=fuzzer,address,undefined)
# Sources by glob, so that a new file in core/ or io/ cannot break the link (io/vtu_writer.cpp,
# io/xdmf_writer.cpp and io/exodus_writer.cpp are left out: they need VTK and HDF5, which no
# reader uses).
CORE=(core/*.cpp)
IO_READERS="$(ls io/*.cpp | grep -v 'vtu_writer\|xdmf_writer\|exodus_writer' | tr '\n' ' ')"
IO_POINTS="$IO_READERS"
IO_SURFACE="$IO_READERS"
ORDERS="$(ls mesher/order/order*.cpp | tr '\n' ' ')"

# target : sources (besides the target file and core) : libraries
declare -A SOURCES=(
  [xyz]="$IO_POINTS"
  [node]="$IO_POINTS"
  [ply_points]="$IO_POINTS"
)
declare -A LIBS=(
  [xyz]=""
  [node]=""
  [ply_points]=""
)
# The surface-reader and YAML-loader targets (listed when their harness file exists).
[ -f tests/fuzz/fuzz_stl.cpp ] && SOURCES[stl]="$IO_SURFACE" && LIBS[stl]=""
[ -f tests/fuzz/fuzz_ply_surface.cpp ] && SOURCES[ply_surface]="$IO_SURFACE" && LIBS[ply_surface]=""
[ -f tests/fuzz/fuzz_obj.cpp ] && SOURCES[obj]="$IO_SURFACE" && LIBS[obj]=""
[ -f tests/fuzz/fuzz_off.cpp ] && SOURCES[off]="$IO_SURFACE" && LIBS[off]=""
# The solver-format readers (round trips of the writers).
[ -f tests/fuzz/fuzz_msh.cpp ] && SOURCES[msh]="$IO_READERS" && LIBS[msh]=""
[ -f tests/fuzz/fuzz_medit.cpp ] && SOURCES[medit]="$IO_READERS" && LIBS[medit]=""
# (mesher/reference/tetgen_delaunay.cpp without KDMESH_WITH_TETGEN is only tetgen_available() and its
# message, which job_config asks for `check: [tetgen]`: no TetGen, no CGAL here.)
[ -f tests/fuzz/fuzz_config.cpp ] && SOURCES[config]="tools/app/job_config.cpp tools/app/job_paths.cpp io/file_io.cpp $ORDERS mesher/reference/tetgen_delaunay.cpp" && LIBS[config]="-lyaml-cpp -lpthread"

targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=($(printf '%s\n' "${!SOURCES[@]}" | sort))
command -v "$CXX" >/dev/null || { echo "fuzz: $CXX not found (apt-get install clang libclang-rt-14-dev)" >&2; exit 2; }

for t in "${targets[@]}"; do
  [ -n "${SOURCES[$t]+x}" ] || { echo "fuzz: unknown target '$t'" >&2; exit 2; }
done

# Each source is compiled once (JOBS at a time) into build-fuzz/obj/, whatever number of targets
# uses it; then each target is linked from its objects. (Compiling every target's sources anew
# took most of this stage's time.)
obj_of() { echo "$OUT/obj/$(echo "$1" | tr '/' '_' | sed 's/\.cpp$/.o/')"; }
mkdir -p "$OUT/obj"
all_sources=("${CORE[@]}")
for t in "${targets[@]}"; do
  # shellcheck disable=SC2206
  all_sources+=("tests/fuzz/fuzz_$t.cpp" ${SOURCES[$t]})
done
mapfile -t unique < <(printf '%s\n' "${all_sources[@]}" | sort -u)
echo "fuzz: compiling ${#unique[@]} sources (${JOBS} at a time)"
export CXX OUT
FLAGS_TEXT="${FLAGS[*]}"
export FLAGS_TEXT
printf '%s\n' "${unique[@]}" | xargs -P "$JOBS" -I{} bash -c \
  'o="$OUT/obj/$(echo "{}" | tr "/" "_" | sed "s/\.cpp$/.o/")"; $CXX $FLAGS_TEXT -c "{}" -o "$o" || { echo "fuzz: compiling {} failed" >&2; exit 255; }'
for t in "${targets[@]}"; do
  objs=("$(obj_of "tests/fuzz/fuzz_$t.cpp")")
  # shellcheck disable=SC2086
  for src in ${SOURCES[$t]} "${CORE[@]}"; do objs+=("$(obj_of "$src")"); done
  echo "fuzz: linking $t"
  # shellcheck disable=SC2086
  "$CXX" "${LINK_FLAGS[@]}" "${objs[@]}" ${LIBS[$t]} -o "$OUT/fuzz_$t"
done

# Each target runs SECONDS_PER_TARGET on one core; JOBS targets at a time.
run_one() {
  local t=$1 exe="$OUT/fuzz_$1" work="$OUT/corpus/$1"
  rm -rf "$work"
  mkdir -p "$work" "$OUT/findings/$t" "$OUT/tmp/$t"
  cp tests/fuzz/corpus/"$t"/* "$work"/ 2>/dev/null || true
  if KDMESH_FUZZ_TMP="$OUT/tmp/$t" "$exe" "$work" -max_total_time="$SECONDS_PER_TARGET" \
        -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=512 -max_len=65536 \
        -artifact_prefix="$OUT/findings/$t/" -print_final_stats=1 > "$OUT/$t.log" 2>&1; then
    echo 0 > "$OUT/$t.status"
  else
    echo 1 > "$OUT/$t.status"
  fi
}
status=0
running=0
for t in "${targets[@]}"; do
  echo "fuzz: running $t for ${SECONDS_PER_TARGET}s"
  run_one "$t" &
  running=$((running + 1))
  if [ "$running" -ge "$JOBS" ]; then
    wait -n || true
    running=$((running - 1))
  fi
done
wait || true
for t in "${targets[@]}"; do
  if [ "$(cat "$OUT/$t.status" 2>/dev/null)" != 0 ]; then
    echo "fuzz: FINDING in $t (log: $OUT/$t.log, reproducer in $OUT/findings/$t/)" >&2
    tail -n 40 "$OUT/$t.log" >&2
    status=1
  else
    echo "fuzz: $t: $(grep -E "stat::number_of_executed_units|stat::new_units_added" "$OUT/$t.log" | tr '\n' ' ')"
  fi
done
exit $status
