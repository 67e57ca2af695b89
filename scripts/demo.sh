#!/usr/bin/env bash
# The demo pipeline, end to end, on data prtkit makes itself:
#   1. sample-shader bakes a procedural HDR sky (testdata/shaders/sky.sl) into a lat-long EXR,
#      with guaranteed per-texel error bounds;
#   2. sh-project projects it onto spherical harmonics (order chosen for ε = 1 %) and writes the
#      reconstruction and the irradiance map;
#   3. prefilter makes a glossy Phong reflection map and a microfacet SHRM from it;
#   4. count-terms says how many in-out BRDF terms those materials need;
#   5. render draws a sphere from the SHRM next to the reference;
#   6. ibl bakes the sky for a glTF/PBR engine (KTX2 mip chain, SH snippets, DFG table);
#   7. render shades a grid of glTF materials from that bake, each next to the ground truth;
#   8. transfer bakes a bowl holding a ball (unshadowed, shadowed, interreflected) and render
#      relights it under two light probes and a turned one, beside the ground truth;
#   9. transfer --factors bakes the same bowl in a glossy material and render relights it, view
#      dependent, beside the factored render and the ground truth.
# Outputs go to out/demo/ (EXR for data, PNG previews for people). Usage: scripts/demo.sh [OUTDIR]
# Each step says what it does in one line; the stages' own notes follow (and, for a phase longer
# than 10 s, how far it is every 10 s), so no step is silent for long.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/demo}
mkdir -p "$out"
say() { printf '\n== %s\n' "$*" >&2; }
# A fresh clone compiles prtkit and its dependencies first (minutes on 2 cores). The build is
# the one `cargo test --release` needs too (the binaries and the tests, one feature set), so the
# README's second command compiles nothing; `narrated_build` says every 20 s that it is still going.
. scripts/lib/build.sh
say "0. building prtkit and its tests (cargo test --release --no-run; minutes the first time, then nothing)"
narrated_build cargo test --release --no-run
bin=target/release

say "1. sample-shader: a procedural sky as a 512x256 lat-long environment"
"$bin/sample-shader" testdata/shaders/sky.sl --latlong 512x256 --tolerance 0.05 \
    -o "$out/sky.exr" --stats "$out/sky.stats.json"
"$bin/prtkit" convert "$out/sky.exr" --to latlong -o "$out/sky.png" --exposure -2

say "2. sh-project: SH coefficients for ε = 1 %, reconstruction and irradiance"
"$bin/sh-project" "$out/sky.exr" --epsilon 0.01 -o "$out/sky.sh.json" \
    --reconstruct "$out/sky-recon.exr" --reconstruct "$out/sky-recon.png" \
    --irradiance "$out/sky-irradiance.exr" --irradiance "$out/sky-irradiance.png" --exposure -4 --json \
    > "$out/sh-project.summary.json"

say "3. prefilter: Phong s=32 reflection map; microfacet (σ = 0.2) SHRM and two views"
# Defaults throughout: orders from the per-texel rule for this lighting, the sun filtered in
# angle apart from the SH remainder, the nonneg window (docs/prefilter.md, "Ring-free bakes").
# The microfacet's two views are integrated in angle beside its SHRM ("Maps in angle").
"$bin/prefilter" "$out/sky.exr" --brdf phong:s=32 --reflection-map "$out/phong32.exr" \
    --reflection-map "$out/phong32.png" --exposure -2 -o "$out/phong32.shrm.json"
"$bin/prefilter" "$out/sky.exr" --brdf torrance-sparrow:sigma=0.2 --size 256x128 \
    --shrm "$out/microfacet.shrm.exr" --view 0,0,1 --reflection-map "$out/microfacet-top.png" \
    --view 1,0,0.2 --reflection-map "$out/microfacet-side.png" --exposure -2 -o "$out/microfacet.shrm.json"

say "4. count-terms: in-out BRDF terms for the demo materials (measured by SVD)"
"$bin/count-terms" --brdf phong:s=32 --brdf torrance-sparrow:sigma=0.2 --resolution 40 \
    --json > "$out/terms.json"
"$bin/count-terms" --brdf phong:s=32 --brdf torrance-sparrow:sigma=0.2 --resolution 40 >&2

say "5. render: a Phong s=32 sphere from the SHRM next to the reference (panel.png)"
"$bin/prefilter" "$out/sky.exr" --brdf phong:s=32 --shrm "$out/phong32.shrm.exr" -o "$out/phong32-render.shrm.json"
# The reference integrates what the SHRM represents (Phong's lobe about R, R&H 2002 §6.3).
"$bin/render" "$out/sky.exr" --brdf phong:s=32 --res 128x128 --eye 0,-4,0.8 --fov 30 --integrand prefilter \
    -o "$out/ref.exr"
"$bin/render" "$out/sky.exr" --brdf phong:s=32 --res 128x128 --eye 0,-4,0.8 --fov 30 --shading shrm \
    --shrm "$out/phong32-render.shrm.json" -o "$out/shrm.exr" --compare "$out/ref.exr" --exposure -2 \
    --panel "$out/panel.png" --panel-item "reference=$out/ref.exr"

say "6. ibl: GGX mip chain, irradiance cube, SH snippets and DFG table for glTF/PBR engines"
# Prints each level's method and its error against the angular integral (also in ibl/ibl.json).
# ibl writes into a new or empty directory (never over another bake): a rerun replaces the demo's own.
rm -rf "$out/ibl"
"$bin/ibl" "$out/sky.exr" -o "$out/ibl"

say "7. render --shading ibl: a roughness x metalness grid from the bake, each above its reference (ibl-grid.png)"
# Each sphere reads ibl/'s KTX2 files as an engine does (split sum); its label says the bake's error
# against the exact split-sum integrals and the error against the rendering equation (docs/ibl.md).
"$bin/render" "$out/sky.exr" --shading ibl --ibl "$out/ibl/ibl.json" --grid --brdf gltf:base=1/0.78/0.34 \
    --res 48x48 --eye 0,-4,0.8 --fov 30 --panel "$out/ibl-grid.png" --exposure -2 --json > "$out/ibl-grid.json"

say "8. transfer + render --shading transfer: a bowl holding a ball relit under two probes and a turned one (transfer-relit.png)"
# Needs the shared light probes (../shared/testdata/envmaps); without them the step says so and is
# skipped. Grace Cathedral is stored upside down (pbrt's convention): flipped upright. Both probes
# are resampled to 128x64, which keeps the ground truth (every texel, with visibility, per pixel)
# to seconds. Order 4 and 512 rays per vertex: low orders need few rays.
probes=../shared/testdata/envmaps
if [ -f "$probes/grace_latlong.exr" ] && [ -f "$probes/uffizi_ict_latlong_256x128.hdr" ]; then
    t="$out/transfer"
    mkdir -p "$t"
    mesh=testdata/meshes/bowl-ball.obj
    "$bin/prtkit" convert "$probes/grace_latlong.exr" --flip-vertical --to latlong --size 128x64 -o "$t/grace.exr"
    "$bin/prtkit" convert "$probes/uffizi_ict_latlong_256x128.hdr" --to latlong --size 128x64 -o "$t/uffizi.exr"
    for mode in unshadowed shadowed interreflected; do
        bounces=(); [ "$mode" = interreflected ] && bounces=(--bounces 2)
        "$bin/transfer" "$mesh" -n 4 --rays 512 --mode "$mode" "${bounces[@]}" --albedo 0.8 \
            --glb "$t/$mode.glb" -o "$t/$mode.json" -q
    done
    # One row per lighting: the reference first, then the three bakes relit and compared with it;
    # the interreflected render lays out the row's panel (its error label says against what).
    view=(--scene "$mesh" --brdf lambert:albedo=0.8 --eye 0,-1.6,3.2 --target 0,0,-0.45 --fov 34 --res 96x96 -q)
    rows=()
    # Each row at its own exposure: Grace is stored about 6 stops darker than the Uffizi probe.
    for row in "grace grace.exr 0 3.5" "uffizi uffizi.exr 0 -2.5" "grace-turned grace.exr 120 3.5"; do
        set -- $row
        name=$1 env="$t/$2" turn=$3 exposure=$4
        title=$([ "$turn" = 0 ] && echo "$name" || echo "grace +${turn}deg")
        "$bin/render" "$env" "${view[@]}" --env-rotation "$turn" -o "$t/$name-reference.exr"
        for mode in unshadowed shadowed; do
            "$bin/render" "$env" "${view[@]}" --env-rotation "$turn" --shading transfer --transfer "$t/$mode.glb" \
                -o "$t/$name-$mode.exr" --compare "$t/$name-reference.exr" --metrics "$t/$name-$mode.metrics.json"
        done
        "$bin/render" "$env" "${view[@]}" --env-rotation "$turn" --shading transfer --transfer "$t/interreflected.glb" \
            -o "$t/$name-interreflected.exr" --compare "$t/$name-reference.exr" --exposure "$exposure" \
            --metrics "$t/$name-interreflected.metrics.json" --panel "$t/$name.png" \
            --panel-item "$title|unshadowed=$t/$name-unshadowed.exr" --panel-item "$title|shadowed=$t/$name-shadowed.exr" \
            --panel-item "$title|interreflected|2 bounces=-" --panel-item "$title|reference, direct=$t/$name-reference.exr"
        rows+=("$t/$name.png")
    done
    "$bin/examples/stack_panels" "$out/transfer-relit.png" "${rows[@]}"

    say "9. transfer --factors: the same bowl in glossy Phong s=8, relit per frame through the in-out factorization (transfer-glossy.png)"
    # factor-brdf factors the BRDF once; transfer keeps the fewest terms holding 99 % of its energy
    # and bakes a K x 64 matrix per vertex (order 8, one ray per cell of the factors' grid); render
    # relights it (K dot products per vertex, h_k per pixel) beside the factored render of the whole
    # probe (no SH) and the ground truth.
    g="$out/transfer-glossy"
    mkdir -p "$g"
    "$bin/factor-brdf" phong:s=8 --domain hemisphere --resolution 32 --cosine --factors "$g/phong8.exr" --terms 32 \
        -o "$g/phong8.json" -q
    "$bin/transfer" "$mesh" -n 8 --factors "$g/phong8.json" --energy 0.99 --glb "$g/glossy.glb" -o "$g/glossy.json" -q
    k=$(sed -n 's/^ *"terms": \([0-9]*\),$/\1/p' "$g/glossy.json" | head -n 1)
    view=(--scene "$mesh" --brdf phong:s=8 --eye 0,-1.6,3.2 --target 0,0,-0.45 --fov 34 --res 96x96 -q)
    rows=()
    for row in "grace grace.exr 0 3.5" "uffizi uffizi.exr 0 -2.5" "grace-turned grace.exr 120 3.5"; do
        set -- $row
        name=$1 env="$t/$2" turn=$3 exposure=$4
        title=$([ "$turn" = 0 ] && echo "$name" || echo "grace +${turn}deg")
        "$bin/render" "$env" "${view[@]}" --env-rotation "$turn" -o "$g/$name-reference.exr"
        # The factored render has no --env-rotation (it projects the probe as stored): the turned
        # row shows the bake and the ground truth.
        factored=()
        if [ "$turn" = 0 ]; then
            "$bin/render" "$env" "${view[@]}" --shading factored --factors "$g/phong8.json" -K "$k" --bright off \
                -o "$g/$name-factored.exr" --compare "$g/$name-reference.exr"
            factored=(--panel-item "$title|factored K=$k|whole probe=$g/$name-factored.exr")
        fi
        "$bin/render" "$env" "${view[@]}" --env-rotation "$turn" --shading transfer --transfer "$g/glossy.glb" \
            -o "$g/$name-transfer.exr" --compare "$g/$name-reference.exr" --exposure "$exposure" \
            --metrics "$g/$name-transfer.metrics.json" --panel "$g/$name.png" \
            --panel-item "$title|transfer K=$k n=8=-" "${factored[@]}" --panel-item "$title|reference=$g/$name-reference.exr"
        rows+=("$g/$name.png")
    done
    "$bin/examples/stack_panels" "$out/transfer-glossy.png" "${rows[@]}"

    say "10. transfer --albedo mesh: a corner's red and green walls bleeding colour onto its floor and ball (transfer-colour.png)"
    # The PLY's vertex colours are the albedo: three transfer vectors per vertex, one per colour
    # channel, so each bounce carries the colour of the surface it leaves. Columns: a grey bake
    # (albedo 0.8), the coloured bake shadowed (no bounce: no bleeding), and interreflected.
    c="$out/transfer-colour"
    mkdir -p "$c"
    corner=testdata/meshes/corner-ball.ply
    "$bin/transfer" "$corner" -n 3 --rays 512 --mode interreflected --bounces 3 --albedo 0.8 \
        --glb "$c/grey.glb" -o "$c/grey.json" -q
    for mode in shadowed interreflected; do
        bounces=(); [ "$mode" = interreflected ] && bounces=(--bounces 3)
        "$bin/transfer" "$corner" -n 3 --rays 512 --mode "$mode" "${bounces[@]}" --albedo mesh \
            --glb "$c/$mode.glb" -o "$c/$mode.json" -q
    done
    view=(--scene "$corner" --eye 2.4,-2.8,1.9 --target -0.3,0.3,0.35 --fov 38 --res 128x128 -q)
    rows=()
    for row in "grace grace.exr 0 3.5" "uffizi uffizi.exr 0 -2" "grace-turned grace.exr 120 3.5"; do
        set -- $row
        name=$1 env="$t/$2" turn=$3 exposure=$4
        title=$([ "$turn" = 0 ] && echo "$name" || echo "grace +${turn}deg")
        "$bin/render" "$env" "${view[@]}" --env-rotation "$turn" --shading transfer --transfer "$c/grey.glb" \
            --brdf lambert:albedo=0.8 -o "$c/$name-grey.exr"
        "$bin/render" "$env" "${view[@]}" --env-rotation "$turn" --shading transfer --transfer "$c/shadowed.glb" \
            -o "$c/$name-shadowed.exr"
        "$bin/render" "$env" "${view[@]}" --env-rotation "$turn" --shading transfer --transfer "$c/interreflected.glb" \
            -o "$c/$name-interreflected.exr" --exposure "$exposure" --panel "$c/$name.png" \
            --panel-item "$title|grey 0.8|3 bounces=$c/$name-grey.exr" \
            --panel-item "$title|vertex colours|shadowed=$c/$name-shadowed.exr" \
            --panel-item "$title|vertex colours|3 bounces=-"
        rows+=("$c/$name.png")
    done
    "$bin/examples/stack_panels" "$out/transfer-colour.png" "${rows[@]}"
else
    printf 'skipped: %s holds no grace_latlong.exr and uffizi_ict_latlong_256x128.hdr\n' "$probes" >&2
fi

say "done: $(ls "$out" | wc -l) files in $out"
ls "$out" >&2
