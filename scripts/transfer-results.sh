#!/usr/bin/env bash
# The transfer stage's numbers (docs/results/transfer.md) and one JSON row per measurement on
# stdout: accuracy against independent derivations (examples/transfer_accuracy.rs: rows with
# "check" unshadowed, shadowed, furnace), the speed of a shadowed and an interreflected bake (grey, and coloured) of a
# bowl holding a ball generated here (about 100 000 vertices; "check": "speed"), the frames per
# second of relighting that mesh from its .glb at order 3 ("check": "relight"), clustered PCA
# of diffuse and glossy bakes ("check": "compression"), and the quantized bakes of the demo's bowl
# ("check": "quantization": size and error for --quantize none, i16, i8).
# Knobs (scripts/README.md): PRTKIT_BIN, PRTKIT_RESULTS, PRTKIT_SMALL=1 (a 650-vertex scene,
# 64 rays, the example's small sizes).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
rings=125 segments=400 rays=1024 accuracy=full
if [ "$small" = 1 ]; then rings=12 segments=24 rays=64 accuracy=small; fi
build --bin transfer --bin render --bin sample-shader --example transfer_accuracy
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

echo "transfer-results: accuracy (examples/transfer_accuracy)…" >&2
"$bin/examples/transfer_accuracy" "$accuracy" >"$tmp/accuracy.jsonl"
cat "$tmp/accuracy.jsonl"

# The scene: scripts/lib/bowl-scene.sh's bowl holding a ball.
source scripts/lib/bowl-scene.sh
bowl_scene "$rings" "$segments" >"$tmp/scene.obj"

# bake NAME MODE ORDER EXTRA...: bakes the scene, prints its speed row, leaves $tmp/NAME-ORDER.{glb,json}.
bake() {
  local name=$1 mode=$2 order=$3 load
  shift 3
  load="$(cut -d' ' -f1 /proc/loadavg 2>/dev/null || echo null)"
  echo "transfer-results: $name ($mode $*), order $order, $rays rays…" >&2
  TIMEFORMAT='%R %U'
  { time "$bin/transfer" "$tmp/scene.obj" -n "$order" --rays "$rays" --mode "$mode" "$@" \
      --glb "$tmp/$name-$order.glb" -o "$tmp/$name-$order.json" --json -q >"$tmp/$name-$order.summary"; } 2>"$tmp/time"
  read -r wall user <"$tmp/time"
  local s="$tmp/$name-$order.summary"
  json_row check=speed name="$name" mode="$mode" order="$order" vertices="$(json_get "$s" vertices)" \
      triangles="$(json_get "$tmp/$name-$order.json" mesh.triangles)" rays="$rays" \
      bounces="$(json_get "$s" bounces)" seconds="$(json_get "$s" seconds)" \
      bounce_seconds="$(json_get "$s" bounce_seconds)" rays_per_second="$(json_get "$s" rays_per_second)" \
      wall="$wall" cpu_user="$user" load_before="$load" | tee "$tmp/speed-$name-$order.row"
}
bake shadowed shadowed 4
bake interreflected interreflected 4 --bounces 2
# A coloured albedo: three transfer vectors per vertex, the rays traced once (docs/transfer.md).
bake interreflected-colour interreflected 4 --bounces 2 --albedo 0.9,0.5,0.2
bake shadowed shadowed 3 >/dev/null # for the relighting at order 3, not a row of the table
rm "$tmp/speed-shadowed-3.row"
"$bin/sample-shader" testdata/shaders/sky.sl --latlong 64x32 -o "$tmp/sky.exr" -q
echo "transfer-results: relighting from the order-3 .glb…" >&2
"$bin/render" "$tmp/sky.exr" --scene "$tmp/scene.obj" --shading transfer --transfer "$tmp/shadowed-3.glb" \
    --res 64x64 --json -q >"$tmp/relight.json"
json_row check=relight order="$(json_get "$tmp/relight.json" transfer.order)" \
    vertices="$(json_get "$tmp/relight.json" transfer.vertices)" frames="$(json_get "$tmp/relight.json" transfer.frames)" \
    frames_per_second="$(json_get "$tmp/relight.json" transfer.frames_per_second)" \
    median_frames_per_second="$(json_get "$tmp/relight.json" transfer.median_frames_per_second)" | tee "$tmp/relight.row"

# compressed NAME MESH RELIGHT_ARGS -- TRANSFER_ARGS...: bakes MESH with TRANSFER_ARGS, relights
# it once (render --json) and prints a row: its size, the CPCA figures from the manifest, the
# frames per second of relighting it.
compressed() {
  local name=$1 mesh=$2 relight_args=$3
  shift 4
  echo "transfer-results: $name…" >&2
  TIMEFORMAT='%R %U'
  { time "$bin/transfer" "$mesh" "$@" --glb "$tmp/$name.glb" -o "$tmp/$name.json" --json -q >"$tmp/$name.summary"; } \
      2>"$tmp/time"
  read -r wall user <"$tmp/time"
  # shellcheck disable=SC2086
  "$bin/render" "$tmp/sky.exr" --scene "$mesh" --shading transfer --transfer "$tmp/$name.glb" $relight_args \
      --res 64x64 --json -q >"$tmp/$name.relight.json"
  local m="$tmp/$name.json"
  jq -c --arg name "$name" --arg wall "$wall" --arg user "$user" --arg bytes "$(wc -c <"$tmp/$name.glb")" \
      --argjson fps "$(json_get "$tmp/$name.relight.json" transfer.frames_per_second)" \
      '{check: "compression", name: $name, vertices: .mesh.vertices, values: (.compression.values_per_vertex // .coefficients),
        terms: (.glossy.terms // 1), clusters: (.compression.clusters // 0), pca: (.compression.components // 0),
        iterations: (.compression.iterations // 0), relative_rms: (.compression.relative_rms // 0),
        max_vertex: (.compression.max_vertex // 0), glb_bytes: ($bytes | tonumber), wall: ($wall | tonumber),
        cpu_user: ($user | tonumber), frames_per_second: $fps}' "$m" | tee "$tmp/$name.row"
  compressed_rows+=("$tmp/$name.row")
}
compressed_rows=()
# Diffuse, order 4, on the scene above; glossy (Phong s = 8, the demo's step 9) on the bowl of
# testdata, whose 1 507 vertices keep the glossy bakes to seconds.
compressed diffuse-full "$tmp/scene.obj" "" -- -n 4 --rays "$rays"
for cp in "64 4" "256 4" "256 8"; do
  set -- $cp
  compressed "diffuse-c$1-p$2" "$tmp/scene.obj" "" -- -n 4 --rays "$rays" --clusters "$1" --pca "$2"
done
"$bin/factor-brdf" phong:s=8 --domain hemisphere --resolution 32 --cosine --factors "$tmp/phong8.exr" --terms 32 \
    -o "$tmp/phong8.json" -q
glossy=(-n 8 --factors "$tmp/phong8.json" --energy 0.99)
compressed glossy-full testdata/meshes/bowl-ball.obj "--brdf phong:s=8" -- "${glossy[@]}"
for cp in "16 8" "64 8" "64 16"; do
  set -- $cp
  compressed "glossy-c$1-p$2" testdata/meshes/bowl-ball.obj "--brdf phong:s=8" -- "${glossy[@]}" --clusters "$1" --pca "$2"
done

# quantized NAME MESH RELIGHT_ARGS -- TRANSFER_ARGS...: bakes MESH with --quantize none, i16 and i8,
# relights each and compares the quantized pictures with the float one; prints a row per bake:
# its size and the manifest's quantization error and bound.
quantized() {
  local name=$1 mesh=$2 relight_args=$3 kind compare
  shift 4
  for kind in none i16 i8; do
    echo "transfer-results: $name, --quantize $kind…" >&2
    "$bin/transfer" "$mesh" "$@" --quantize "$kind" --glb "$tmp/q-$name-$kind.glb" -o "$tmp/q-$name-$kind.json" -q
    compare=()
    [ "$kind" = none ] || compare=(--compare "$tmp/q-$name-none.exr" --metrics "$tmp/q-$name-$kind.metrics.json")
    # shellcheck disable=SC2086
    "$bin/render" "$tmp/sky.exr" --scene "$mesh" --shading transfer --transfer "$tmp/q-$name-$kind.glb" $relight_args \
        --res 64x64 -o "$tmp/q-$name-$kind.exr" -q "${compare[@]}"
    jq -c --arg name "$name" --arg bytes "$(wc -c <"$tmp/q-$name-$kind.glb")" \
        --argjson image "$(if [ "$kind" = none ]; then echo 0; else json_get "$tmp/q-$name-$kind.metrics.json" metrics.rel_error; fi)" \
        '{check: "quantization", name: $name, quantize: (.quantization.method // "none"), vertices: .mesh.vertices,
          values: (.compression.values_per_vertex // .coefficients), clusters: (.compression.clusters // 0),
          pca: (.compression.components // 0), cpca_relative_rms: (.compression.relative_rms // 0),
          relative_rms: (.quantization.relative_rms // 0), relative_rms_bound: (.quantization.relative_rms_bound // 0),
          glb_bytes: ($bytes | tonumber), image_relative_rms: $image}' "$tmp/q-$name-$kind.json" | tee "$tmp/q-$name-$kind.row"
    quantized_rows+=("$tmp/q-$name-$kind.row")
  done
}
quantized_rows=()
quantized diffuse testdata/meshes/bowl-ball.obj "" -- -n 4 --rays "$rays"
quantized diffuse-c32-p4 testdata/meshes/bowl-ball.obj "" -- -n 4 --rays "$rays" --clusters 32 --pca 4
quantized glossy testdata/meshes/bowl-ball.obj "--brdf phong:s=8" -- "${glossy[@]}"
quantized glossy-c64-p16 testdata/meshes/bowl-ball.obj "--brdf phong:s=8" -- "${glossy[@]}" --clusters 64 --pca 16

out="$docs/results/transfer.md"
acc="$tmp/accuracy.jsonl"
{
  echo "## Transfer: accuracy and speed"
  echo
  echo "Written by \`scripts/transfer-results.sh\` ($("$bin/transfer" --version)); the accuracy rows come from"
  echo "\`examples/transfer_accuracy.rs\`, the speed rows from the binaries' \`--json\` summaries."
  echo
  echo "### Unshadowed transfer against Â_l"
  echo
  echo "A UV sphere, order 8, albedo 0.8: largest |T_lm − (ρ/π) Â_l Y_lm(n)| over every vertex and"
  echo "coefficient, Â_l typed in from Ramamoorthi & Hanrahan 2001."
  echo
  echo "| order | vertices | largest error |"
  echo "| --- | --- | --- |"
  jq -r 'select(.check == "unshadowed") | "| \(.order) | \(.vertices) | \(.max_abs_error) |"' "$acc"
  echo
  echo "### Shadowed transfer against a brute-force integral"
  echo
  echo "A bowl holding a ball; the reference tests every triangle in double precision for each"
  echo "direction of a Gauss–Legendre × azimuth rule in world axes (no BVH, not the stage's rays);"
  echo "relative RMS over the sampled vertices and every coefficient."
  echo
  echo "| order | rays | vertices (of) | reference directions | relative RMS |"
  echo "| --- | --- | --- | --- | --- |"
  jq -r 'select(.check == "shadowed") | "| \(.order) | \(.rays) | \(.vertices) (\(.of)) | \(.directions) | \(.relative_rms * 10000 | round / 100) % |"' "$acc"
  echo
  echo "### White furnace: interreflection inside a closed sphere"
  echo
  echo "Inward normals, the unshadowed transfer as the source term, albedo ρ: every bounce"
  echo "multiplies the constant-lighting response by ρ, so the total is T⁰ (1 + ρ + … + ρ^B)."
  echo "\"lost\" is the share of rays that slipped through a crack between triangles (single-precision"
  echo "traversal) and carried no bounce."
  echo
  echo "| ρ | bounces B | rays | vertices | lost | mean total / T⁰ | 1 + ρ + … + ρ^B | largest relative error | mean relative error |"
  echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
  jq -r 'select(.check == "furnace") | "| \(.albedo) | \(.bounces) | \(.rays) | \(.vertices) | \(.lost_rays) | \(.total * 1000000 | round / 1000000) | \(.series * 1000000 | round / 1000000) | \(.max_relative_error) | \(.mean_relative_error) |"' "$acc"
  echo
  echo "### Speed"
  echo
  echo "The bowl-and-ball scene at ${rings} rings × ${segments} segments per object, order 4, $rays rays"
  echo "per vertex, all threads. \`seconds\` is the stage's own (BVH build, rays, bounces); wall and"
  echo "CPU are the process's (reading the OBJ, writing the .glb). The machine is shared: the load"
  echo "average before each run says how much of its 2 cores the run had."
  echo
  echo "| bake | vertices | triangles | rays | seconds | of which bounces | rays/s (first pass) | wall s | CPU user s | load before |"
  echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
  for f in "$tmp/speed-shadowed-4.row" "$tmp/speed-interreflected-4.row" "$tmp/speed-interreflected-colour-4.row"; do
    jq -r '"| \(.name) | \(.vertices) | \(.triangles) | \(.rays) | \(.seconds * 10 | round / 10) | \(.bounce_seconds * 10 | round / 10) | \(.rays_per_second / 1e6 * 100 | round / 100) M | \(.wall) | \(.cpu_user) | \(.load_before) |"' "$f"
  done
  echo
  jq -rs 'map({(.mode): .}) | add | "Interreflected with 2 bounces took \(.interreflected.seconds / .shadowed.seconds * 100 | round / 100)× the shadowed bake (CPU \(.interreflected.cpu_user / .shadowed.cpu_user * 100 | round / 100)×). Issue 32'"'"'s targets: shadowed ≤ 30 s on this 2-core machine, interreflected ≤ 3× that, relighting ≥ 200 frames/s."' \
      "$tmp/speed-shadowed-4.row" "$tmp/speed-interreflected-4.row"
  echo
  jq -rs 'map({(.name): .}) | add | "With a coloured albedo (`--albedo 0.9,0.5,0.2`: three transfer vectors per vertex, the rays traced once and the three channels gathered over the same hits) the interreflected bake took \(.["interreflected-colour"].seconds / .interreflected.seconds * 100 | round / 100)× the grey one, its bounces \(.["interreflected-colour"].bounce_seconds / .interreflected.bounce_seconds * 100 | round / 100)×."' \
      "$tmp/speed-interreflected-4.row" "$tmp/speed-interreflected-colour-4.row"
  echo
  echo "Relighting from the order-3 \`.glb\` of the same scene (\`render --shading transfer --json\`):"
  echo "each frame is an SH rotation of the lighting and the 9-term dot product at every vertex, one"
  echo "thread, single precision."
  echo
  echo "| order | vertices | frames | frames/s (fastest) | frames/s (median) |"
  echo "| --- | --- | --- | --- | --- |"
  jq -r '"| \(.order) | \(.vertices) | \(.frames) | \(.frames_per_second | round) | \(.median_frames_per_second | round) |"' "$tmp/relight.row"
  echo
  echo "### Clustered PCA (\`--clusters C --pca P\`)"
  echo
  echo "Sloan, Hall, Hart & Snyder 2003: each vertex keeps its cluster and P weights, each cluster"
  echo "its mean and P directions. Diffuse: the scene above at order 4 ($rays rays). Glossy: the demo's"
  echo "bowl (\`testdata/meshes/bowl-ball.obj\`) in Phong s = 8 factored at 32² cells, K from 99 % of"
  echo "the energy, order 8. Error: ‖T − T̃‖/‖T‖ over every value (relative RMS) and the largest"
  echo "per-vertex ‖T − T̃‖ over the RMS of ‖T‖, from the manifest. Seconds: the whole \`transfer\`"
  echo "run (rays and compression). Frames/s: \`render --shading transfer --json\`'s relighting (one"
  echo "thread: per frame the SH rotation and the dot products, per cluster then per vertex when"
  echo "compressed)."
  echo
  echo "| bake | vertices | values per vertex | C | P | rounds | relative RMS | largest vertex | .glb MB | wall s | frames/s |"
  echo "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
  for f in "${compressed_rows[@]}"; do
    jq -r '"| \(.name) | \(.vertices) | \(.values) | \(.clusters) | \(.pca) | \(.iterations) | \(.relative_rms * 10000 | round / 100) % | \(.max_vertex * 10000 | round / 100) % | \(.glb_bytes / 1e4 | round / 100) | \(.wall) | \(.frames_per_second | round) |"' "$f"
  done
  echo
  echo "### Quantization (\`--quantize none|i16|i8\`)"
  echo
  echo "The demo's bowl (\`testdata/meshes/bowl-ball.obj\`, 1 507 vertices): diffuse at order 4 ($rays rays),"
  echo "and glossy as above; each uncompressed and compressed. i16 stores the per-vertex values"
  echo "(\`_PRT_k\`, or the weights \`_PRT_W_k\` when compressed) as normalized SHORT, i8 as normalized"
  echo "BYTE, with a scale per value index (per cluster when compressed). Quantization error: the"
  echo "manifest's ‖T̂ − T_float‖/‖T‖ (T_float the transfer the float file holds: the CPCA reconstruction"
  echo "when compressed), and its closed-form bound from half a code step per value. Relit picture:"
  echo "relative RMS of \`render --shading transfer\` of the bake against the float bake's picture (the"
  echo "sky, 64 × 64, \`render --compare\`)."
  echo
  echo "| bake | quantize | values per vertex | C | P | .glb kB | quantization error | its bound | CPCA error | relit picture vs float |"
  echo "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
  for f in "${quantized_rows[@]}"; do
    jq -r '"| \(.name) | \(.quantize) | \(.values) | \(.clusters) | \(.pca) | \(.glb_bytes / 1e3 | round) | \(.relative_rms * 1e6 | round / 1e4) % | \(.relative_rms_bound * 1e6 | round / 1e4) % | \(.cpca_relative_rms * 1e4 | round / 100) % | \(.image_relative_rms * 1e6 | round / 1e4) % |"' "$f"
  done
} >"$out"
echo "wrote $out" >&2
