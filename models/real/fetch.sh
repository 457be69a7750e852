#!/usr/bin/env bash
# kdmesh — fetches real CAD and scanned surfaces that Debian 12 packages ship, into models/real/.
# SPDX-License-Identifier: AGPL-3.0-or-later
#
#   bash models/real/fetch.sh           download, extract, check sums, convert OFF -> PLY
#   bash models/real/fetch.sh --check   the same, then run models/check_stl.py on each file
#   bash models/real/fetch.sh --list    print "file<TAB>package<TAB>path<TAB>flag" per entry, no download
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
if [ "${1:-}" = "--list" ]; then
  grep -E '^  "[^"]+\|[^"]+"$' "${BASH_SOURCE[0]}" | sed -E 's/^  "(.*)"$/\1/' |
    while IFS='|' read -r p path out sum flag; do
      printf '%s\t%s\t%s\t%s\n' "$out" "$p" "$path" "${flag:-bench}"
    done
  exit 0
fi

# package | path inside the .deb (a .tar.gz member is given as TARBALL::MEMBER) | output name | sha256 of the source file | flag
# flag: "bench" = a valid solid (closed, 2-manifold, outward, no self-intersection, per
# models/check_stl.py) that tools/bench/real_parts.sh meshes; "invalid:REASON" = kept on purpose
# (kdmesh must reject it cleanly), skipped by the benchmark.
FILES=(
  "netgen-doc|usr/share/doc/netgen/examples/hinge.stl|hinge.stl|6a3dad078e4a2e438f4bf99c876eee7e0a6af1db738945ad4e63a40eaec4958d|bench"
  "netgen-doc|usr/share/doc/netgen/examples/part1.stl|part1.stl|dcd928df68ae73ef41bd18cd784edc8973fb22ac11a3547d9acd83ec3d79c4a6|bench"
  "gmsh-doc|usr/share/doc/gmsh-doc/converters/stl_to_cartesian/lever.stl.gz|lever.stl|354c41a03232b77d98ef825c1dd484cb84a193b80da6af647d4ecd51aa28381c|bench"
  "gmsh-doc|usr/share/doc/gmsh-doc/doc/gmsh/tutorial/t13_data.stl.gz|t13_data.stl|4b9431c0dddde5b7e4f6b09506443c7ae1e3134646e2a9447e09a77379fdbd70|bench"
  "gmsh-doc|usr/share/doc/gmsh-doc/doc/gmsh/demos/api/object.stl.gz|object.stl|f356820d5d20f4595f642b6e76e30e6536307bf8dad4282fb37c842108550540|invalid:8 open edges at a seam, 8 intersecting facet pairs"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/fandisk.off|fandisk.ply|edffb263f037b023757259befd5532fccb48bdc3c35a1da2e11e235a647bd050|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/couplingdown.off|couplingdown.ply|01fc9017b44a803b1130f8f5d51f0c7d8bbfa27b908f5166c498fe21e57f2284|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/femur.off|femur.ply|75d208fabf7a7b134cfcf2171bad68c331e3bff55309ffe38a01a7b31352fbc6|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/elephant.off|elephant.ply|be4e1ea68f5f840a3d2ada69d828222e76a57d9e25b21e19a9deacd3f2328e02|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/pig.stl|pig.stl|584a6e2684053f4112865544115b60a8b3efb66917312db6608d9a152cf30406|invalid:17 shells, open edges, 70 intersecting facet pairs"
  # issue 18 item 5: more CAD parts and scans, each checked valid by models/check_stl.py
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/anchor.off|anchor.ply|5009b3400b73ef199b6ac9a24a27f4f76e1aa7b71d957a50cb6dcbe09868ff3b|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/joint.off|joint.ply|a412da1a4b90a1d018d44e0b06307ee692da4afd255975d2a93945e091098649|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/pinion.off|pinion.ply|191a8cdfa3807e09d7dffb4bdc94dabe1231b4594001ca134100a9a32e996599|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/rotor.off|rotor.ply|8db85ca5041eef6d952e48f0553a25fddb42f237b80a37b7aff096b8df3aca32|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/spool.off|spool.ply|84ec2367becf6994f96055fa88aaf3a00df1fdd84bd0fa615bdc043c9944b7b1|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/handle.off|handle.ply|df86377baeaa1ed1a437710e0364a72af06d3bca21b84a57cd1b46a64f67f054|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/dragknob.off|dragknob.ply|4411436ff04757c16ad1c08d631c86ef7e968f1e026193e668c66a19951ca10c|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/oblong.off|oblong.ply|1024a074f8ff0896c3a7ab5bcac72b6f03a69ab71b2fbf3edbd206b2acbd928e|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/part.off|cgal_part.ply|ffec9fae51770a524bd973724bb69babf3cae11ef7564fb630790cb64a75b00b|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/turbine.off|turbine.ply|8ae52b6b325a05e0755983706ab55aba0f42d3ea0569dd29b33cdcb16c20f4c8|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/homer.off|homer.ply|99396cceb6f97e9681545d5c718d4ed87da3ceb78d22afb0218d570e9f0a0873|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/retinal.off|retinal.ply|02547bcd1f28149862ff28056614418c0fca73033dfec1a07e8e91e4c78544b7|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/triceratops.off|triceratops.ply|0fb444933884486a09eb4329a832f15ab792590f2a5bb75385d157e654ddbf5c|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/hand.off|hand.ply|cfcf1562726167ca704a091a8651bfd1d72f6eb96b4b2819321f0520721b35c7|bench"
  "libcgal-demo|usr/share/doc/libcgal-dev/data.tar.gz::data/meshes/helmet.off|helmet.ply|0669ab781a80570cfdd2932b06a7c33f89fd855a9ddb69dc45e50082253a5a32|bench"
  "occt-misc|usr/share/opencascade/data/stl/sh1.stl|occt_sh1.stl|c5bdf0f5ca546f82bebe87205a225ab279d155469e1cd158efb12a968ed7c1c1|bench"
  "occt-misc|usr/share/opencascade/data/stl/sh2.stl|occt_sh2.stl|0bb606ff96255e731a7657ca8aa6c562e1514356fa476d1f4b7551f4ece77364|bench"
  "occt-misc|usr/share/opencascade/data/stl/shape.stl|occt_shape.stl|41793c78563624205829ef9877cc9d9f12ce9cf87ab229a786731600465734b6|bench"
)
# Checked and left out (models/check_stl.py or the edge count of tools/bench/verify_tets.py
# --surface; not in FILES):
#   libcgal-demo data/meshes: camel, bull, elk (self-intersecting facet pairs); cow (a
#     non-manifold vertex and intersecting facets); bones (intersecting facets, a shell inside
#     another); blade (240 open edges); mech-holes-shark (304 open edges); ALSTOM_TEST4 (231
#     open edges); lion, lion-head, mushroom, nefertiti, mask_cone, head, holes, horizons,
#     elephant-with-holes, cylinder, cylinder_locally_refined, blobby_3cc, b9_mesh, boeing
#     (open edges); ChineseDragon-10kv, mannequin-devil (open edges, near-flat slivers);
#     cactus, dino (not OFF: no header); the primitives (cube, sphere, tetrahedra, ...) are
#     valid but not parts; armadillo, bunny00, bear, refined_elephant, man, diplodocus are
#     valid scans, left out for the benchmark's run time.
#   occt-misc data/stl: bearing, motor (open edges, degenerate facets, repeated directed
#     edges), head (10,979 open edges), TR12J_OCC64K (6 open edges); TR12J_OCC is valid
#     (26,966 facets), left out for run time.
#   dart-doc (data/urdf): KR5 base_link, shoulder and WAM wam1-7 (open edges); KR5 bicep,
#     elbow, forearm, palm, wrist and wam_base are valid, left out (the corpus has enough
#     CAD parts; candidates for a larger run).
#   gmsh-doc demos/api: aneurysm_data, terrain_stl_data, surface1, surface2 (open surfaces).
# where each package keeps its copyright file
declare -A COPYRIGHT=(
  [netgen-doc]=usr/share/doc/netgen-doc/copyright
  [gmsh-doc]=usr/share/doc/gmsh-doc/copyright
  [libcgal-demo]=/usr/share/doc/libcgal-dev/copyright  # libcgal-demo's own doc dir has none
  [occt-misc]=usr/share/doc/occt-misc/copyright
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
  IFS='|' read -r p path out sum _flag <<<"$f"
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
    IFS='|' read -r p path out sum _flag <<<"$f"
    python3 "$here/../check_stl.py" "$here/$out" || true
  done
fi
