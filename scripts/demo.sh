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
#   7. render shades a grid of glTF materials from that bake, each next to the ground truth.
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

say "done: $(ls "$out" | wc -l) files in $out"
ls "$out" >&2
