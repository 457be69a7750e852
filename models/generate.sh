#!/usr/bin/env bash
# kdmesh — regenerates the shipped model surfaces (models/*/*.stl) from their OpenSCAD sources.
# SPDX-License-Identifier: AGPL-3.0-or-later
#
#   bash models/generate.sh           install OpenSCAD if missing, regenerate every STL,
#                                     print the facet counts
#   bash models/generate.sh --check   the same, then validate every STL with check_stl.py
#                                     (closed, 2-manifold, outward, no self-intersection,
#                                     clearance between bodies; ~1 min)
#
# Output is binary STL (OpenSCAD's "binstl"), with the facets sorted by canonical_stl.py,
# because OpenSCAD emits them in a run-dependent order: the same OpenSCAD version then gives
# byte-identical files. The committed STLs were made with Debian 12's OpenSCAD 2021.01.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"
check=0
[ "${1:-}" = "--check" ] && check=1

# Same approach as tools/setup.sh's install_deps.
PACKAGES=(openscad)
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "generate: installing ${missing[*]}"
  sudo=()
  [ "$(id -u)" -eq 0 ] || sudo=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo[@]}" apt-get update -qq
  "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
echo "generate: $(openscad --version 2>&1)"

# Each output: its STL path (no extension) and its source, with the part to render ("" = the
# whole file). The gear box assembly's parts come from gearbox.scad's `part` variable.
MODELS=(gearbox/gearbox block/block gearbox/housing gearbox/gear gearbox/shaft gearbox/bearing_a gearbox/bearing_b)
SOURCES=(gearbox/gearbox block/block gearbox/gearbox gearbox/gearbox gearbox/gearbox gearbox/gearbox gearbox/gearbox)
PARTS=("" "" housing gear shaft bearing_a bearing_b)
for i in "${!MODELS[@]}"; do
  m="${MODELS[$i]}"
  tmp="$m.tmp-$$.stl"
  define=()
  [ -n "${PARTS[$i]}" ] && define=(-D "part=\"${PARTS[$i]}\"")
  openscad -q --export-format binstl "${define[@]}" -o "$tmp" "${SOURCES[$i]}.scad"
  # OpenSCAD's facet order varies from run to run: sort it (canonical_stl.py)
  python3 canonical_stl.py "$tmp" "$m.stl" "$(basename "$m")"
  rm -f "$tmp"
  # binary STL: 80-byte header, uint32 facet count, 50 bytes per facet
  n=$(od -An -t u4 -j 80 -N 4 "$m.stl" | tr -d ' ')
  printf 'generate: models/%s.stl  %8d facets  %9d bytes\n' "$m" "$n" "$(stat -c %s "$m.stl")"
done

# The gear box's parts touch on faces that OpenSCAD rounds differently part by part (a float32
# ulp): make them coincide exactly (weld_parts.py), then sort each again.
PARTS_IN_ORDER=(gearbox/housing gearbox/gear gearbox/shaft gearbox/bearing_a gearbox/bearing_b)
python3 weld_parts.py 2e-5 "${PARTS_IN_ORDER[@]/%/.stl}"
for m in "${PARTS_IN_ORDER[@]}"; do python3 canonical_stl.py "$m.stl" "$m.stl" "$(basename "$m")"; done

if [ $check -eq 1 ]; then
  for m in "${MODELS[@]}"; do
    python3 check_stl.py --clearance "$m.stl"
  done
fi
