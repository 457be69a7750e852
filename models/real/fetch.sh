#!/usr/bin/env bash
# kdmesh — fetches real CAD and scanned surfaces that Debian 12 packages ship, into models/real/.
# SPDX-License-Identifier: AGPL-3.0-or-later
#
#   bash models/real/fetch.sh           download, extract, check sums, convert OFF -> PLY
#   bash models/real/fetch.sh --check   the same, then run models/check_stl.py on each file
#
# The files are third-party data and are not committed (models/real/.gitignore); this script
# is the record of where each one comes from. It uses `apt-get download` (no installation:
# the .debs are only unpacked into a temporary directory) and needs the apt lists (it runs
# `apt-get update` once if a package is unknown; root or sudo for that). Each source file's
# SHA-256 is checked against the one recorded here (Debian 12 versions below); a mismatch is
# reported and the file is still copied. The packages' copyright files are copied to
# models/real/copyright/. OFF files are converted to ASCII PLY (kdmesh reads STL and PLY)
# with off_to_ply.py, which keeps every coordinate's text. Licences: see docs/models.md.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
check=0
[ "${1:-}" = "--check" ] && check=1

# package | path inside the .deb (a .tar.gz member is given as TARBALL::MEMBER) | output name | sha256 of the source file
FILES=(
  "netgen-doc|usr/share/doc/netgen/examples/hinge.stl|hinge.stl|6a3dad078e4a2e438f4bf99c876eee7e0a6af1db738945ad4e63a40eaec4958d"
  "netgen-doc|usr/share/doc/netgen/examples/part1.stl|part1.stl|dcd928df68ae73ef41bd18cd784edc8973fb22ac11a3547d9acd83ec3d79c4a6"
  "gmsh-doc|usr/share/doc/gmsh-doc/converters/stl_to_cartesian/lever.stl.gz|lever.stl|354c41a03232b77d98ef825c1dd484cb84a193b80da6af647d4ecd51aa28381c"
  "gmsh-doc|usr/share/doc/gmsh-doc/doc/gmsh/tutorial/t13_data.stl.gz|t13_data.stl|4b9431c0dddde5b7e4f6b09506443c7ae1e3134646e2a9447e09a77379fdbd70"
  "gmsh-doc|usr/share/doc/gmsh-doc/doc/gmsh/demos/api/object.stl.gz|object.stl|f356820d5d20f4595f642b6e76e30e6536307bf8dad4282fb37c842108550540"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/fandisk.off|fandisk.ply|edffb263f037b023757259befd5532fccb48bdc3c35a1da2e11e235a647bd050"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/couplingdown.off|couplingdown.ply|01fc9017b44a803b1130f8f5d51f0c7d8bbfa27b908f5166c498fe21e57f2284"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/femur.off|femur.ply|75d208fabf7a7b134cfcf2171bad68c331e3bff55309ffe38a01a7b31352fbc6"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/elephant.off|elephant.ply|be4e1ea68f5f840a3d2ada69d828222e76a57d9e25b21e19a9deacd3f2328e02"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/pig.stl|pig.stl|584a6e2684053f4112865544115b60a8b3efb66917312db6608d9a152cf30406"
)
# where each package keeps its copyright file
declare -A COPYRIGHT=(
  [netgen-doc]=usr/share/doc/netgen-doc/copyright
  [gmsh-doc]=usr/share/doc/gmsh-doc/copyright
  [libcgal-demo]=/usr/share/doc/libcgal-dev/copyright  # libcgal-demo's own doc dir has none
)

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

pkgs=()
for f in "${FILES[@]}"; do
  p="${f%%|*}"
  [[ " ${pkgs[*]} " == *" $p "* ]] || pkgs+=("$p")
done

sudo=()
[ "$(id -u)" -eq 0 ] || sudo=(sudo)
for p in "${pkgs[@]}"; do
  if ! apt-cache show "$p" >/dev/null 2>&1; then
    echo "fetch: '$p' unknown to apt; running apt-get update"
    "${sudo[@]}" apt-get update -qq
    break
  fi
done

for p in "${pkgs[@]}"; do
  echo "fetch: downloading $p ($(apt-cache policy "$p" | awk '/Candidate/ {print $2}'))"
  (cd "$work" && apt-get download -q "$p" 2>&1 | grep -v '^W: Download is performed unsandboxed' || true)
  deb=$(ls "$work"/"${p}"_*.deb 2>/dev/null | head -1)
  [ -n "$deb" ] || { echo "fetch: could not download $p" >&2; exit 1; }
  mkdir -p "$work/$p"
  dpkg-deb -x "$deb" "$work/$p"
done

mkdir -p "$here/copyright"
for p in "${pkgs[@]}"; do
  src="${COPYRIGHT[$p]}"
  [[ "$src" == /* ]] || src="$work/$p/$src"
  if [ -f "$src" ]; then
    cp "$src" "$here/copyright/$p"
  else
    echo "fetch: warning: no copyright file for $p at $src (libcgal-dev installs it)" >&2
  fi
done

mismatch=0
for f in "${FILES[@]}"; do
  IFS='|' read -r p path out sum <<<"$f"
  src="$work/$p/$path"
  if [[ "$path" == *::* ]]; then
    tarball="$work/$p/${path%%::*}"
    member="${path#*::}"
    tar -xzf "$tarball" -C "$work/$p" "$member"
    src="$work/$p/$member"
  fi
  raw="$work/raw-$(basename "${src%.gz}")"
  if [[ "$src" == *.gz ]]; then gzip -dc "$src" >"$raw"; else cp "$src" "$raw"; fi
  got=$(sha256sum "$raw" | cut -d' ' -f1)
  if [ "$got" != "$sum" ]; then
    echo "fetch: warning: $(basename "$raw") from $p has sha256 $got, expected $sum" >&2
    mismatch=1
  fi
  case "$raw" in
    *.off) python3 "$here/off_to_ply.py" "$raw" "$here/$out" ;;
    *) cp "$raw" "$here/$out.tmp-$$" && mv -f "$here/$out.tmp-$$" "$here/$out" ;;
  esac
  echo "fetch: models/real/$out  <- $p:/$path"
done
[ $mismatch -eq 0 ] || echo "fetch: some files differ from the recorded versions (see above)" >&2

if [ $check -eq 1 ]; then
  for f in "${FILES[@]}"; do
    IFS='|' read -r p path out sum <<<"$f"
    python3 "$here/../check_stl.py" "$here/$out" || true
  done
fi
