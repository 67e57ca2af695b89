#!/usr/bin/env bash
# A checker, not a results script: the bytes every stage writes, as one sha256 list, so that a
# refactor that promises "no output changes" can show it. Runs the demo (scripts/demo.sh), the
# default `prefilter` reflection map of every shared light probe (the ring-free table's maps),
# `ibl` on the Grace probe, and `transfer` on the test mesh, into OUTDIR, then prints
# `sha256  path` for every file, sorted. JSON documents are hashed with their timing fields
# (any key ending in `seconds`, and `timings`) removed, since those change from run to run, and
# OUTDIR written as `OUT` and the repository's root as `REPO` wherever a file records a path (the
# documents' provenance names the binary that wrote them, which may be another checkout's).
#
#   scripts/output-hashes.sh /tmp/hashes > before.txt    # on the old commit
#   scripts/output-hashes.sh /tmp/hashes > after.txt     # on the new one
#   diff before.txt after.txt                            # empty: the same bytes
#
# Use the same OUTDIR both times: a .glb records the path of the factors it was baked from, and a
# path of another length pads its JSON chunk differently.
#
# Knobs: PRTKIT_BIN=DIR runs the binaries in DIR and builds nothing (scripts/README.md).
set -euo pipefail
out=${1:?usage: scripts/output-hashes.sh OUTDIR}
source "$(dirname "$0")/lib/common.sh"
case "$out" in /*) ;; *) out=$caller_dir/$out ;; esac
build --bins
shared=../shared/testdata/envmaps
rm -rf "$out"
mkdir -p "$out/probes"

echo "output-hashes: the demo" >&2
PRTKIT_BIN=$bin bash scripts/demo.sh "$out/demo" > "$out/demo.log" 2>&1

if [ -d "$shared" ]; then
  echo "output-hashes: default prefilter maps of the shared probes" >&2
  for probe in "$shared/grace_latlong.exr" "$shared/uffizi_ict_latlong_256x128.hdr" \
      "$shared/dxsdk_cubes/grace" "$shared/dxsdk_cubes/stpeters"; do
    name=$(basename "$probe" | sed 's/\.[a-z]*$//')
    name=$(basename "$(dirname "$probe")")-$name
    "$bin/prefilter" "$probe" --brdf phong:s=64 --reflection-map "$out/probes/$name.phong64.exr" \
      -o "$out/probes/$name.phong64.shrm.json" -q
    "$bin/prefilter" "$probe" --brdf torrance-sparrow:sigma=0.1 --size 256x128 \
      --shrm "$out/probes/$name.ts.shrm.exr" -o "$out/probes/$name.ts.shrm.json" -q
  done
  echo "output-hashes: ibl on the Grace probe" >&2
  "$bin/ibl" "$shared/grace_latlong.exr" --size 64 -o "$out/ibl" -q
  "$bin/ibl" "$shared/grace_latlong.exr" --size 64 --samples 0 --container dds --format b10g11r11 \
    -o "$out/ibl-dds" -q
else
  echo "output-hashes: ../shared/testdata/envmaps is absent; the probes are left out" >&2
fi

echo "output-hashes: transfer on the test mesh" >&2
"$bin/transfer" testdata/meshes/floor-ball.obj --mode interreflected --bounces 2 --rays 64 \
  --glb "$out/transfer.glb" -o "$out/transfer.json" --glsl "$out/transfer.glsl" -q
"$bin/transfer" testdata/meshes/floor-ball.obj --mode shadowed --rays 64 --clusters 8 --pca 4 \
  --glb "$out/transfer-cpca.glb" -o "$out/transfer-cpca.json" -q
"$bin/transfer" testdata/meshes/floor-ball.obj --mode shadowed --rays 64 -o "$out/lightmap.json" --glb "$out/lightmap.glb" \
  --lightmap 64x64 "$out/lightmap.exr" -q

repo=$PWD
cd "$out"
find . -type f ! -name '*.log' | sort | while read -r file; do
  case "$file" in
    *.json) hash=$(jq -S 'walk(if type == "object" then with_entries(select((.key | test("seconds$|^timings$")) | not)) else . end)' \
      "$file" | sed "s|$out|OUT|g; s|$repo|REPO|g" | sha256sum | cut -d' ' -f1) ;;
    *) hash=$(sed "s|$out|OUT|g; s|$repo|REPO|g" "$file" | sha256sum | cut -d' ' -f1) ;;
  esac
  echo "$hash  $file"
done
