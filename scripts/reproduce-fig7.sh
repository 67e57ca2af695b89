#!/usr/bin/env bash
# Ramamoorthi & Hanrahan 2002, Fig. 7: the simplified microfacet BRDF (eq. 11, σ = 0.2) rendered
# from SHRMs with P = 0, 1, 2, 3 (F_B = 30, as in the paper) for two views, next to the exact
# image: a full hemispherical integral per pixel (every probe texel, L ρ cos θ_i). Prints one
# JSON line per (view, P), {"view", "p", "brdf_energy", "rel_error", "psnr"}; writes
# docs/render-fig7-{top,side}.png and docs/results/render-fig7.md.
# Usage: scripts/reproduce-fig7.sh [RES]   (default 128: 128x128 pixels)
# Knobs (scripts/README.md): PRTKIT_BIN, PRTKIT_RESULTS, PRTKIT_SMALL=1 (16x16 pixels).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
res="${1:-128}"
if [ "$small" = 1 ]; then res=16; fi
build --bin render --bin prefilter --bin sample-shader
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
source scripts/lib/light-probe.sh
brdf=torrance-sparrow:sigma=0.2
# Two views, each with one view direction for the whole image as in the paper (its (θ̄_o, φ̄_o)):
# a distant camera with a narrow field, so the global SHRM's single reflection map per view
# (eq. 12) is the right model. From the side, 11° above the horizon, and from 17° off the top.
views=("side=0,-40,8" "top=0,-12,38")
for p in 0 1 2 3; do
    "$bin/prefilter" "$env" --brdf "$brdf" --order "30,$p" --global --shrm "$tmp/p$p.shrm.exr" \
        -o "$tmp/p$p.shrm.json" -q
done
table=()
for v in "${views[@]}"; do
    name="${v%%=*}"
    eye="${v#*=}"
    common=(--brdf "$brdf" --res "${res}x${res}" --eye "$eye" --fov 3.2 -q)
    "$bin/render" "$env" "${common[@]}" --shading reference -o "$tmp/$name-ref.exr"
    items=()
    for p in 0 1 2 3; do
        extra=()
        if [ "$p" = 3 ]; then
            extra=(--panel "$docs/render-fig7-$name.png" --exposure 2 "${items[@]}" --panel-item "P=3=-"
                --panel-item "exact=$tmp/$name-ref.exr")
        fi
        "$bin/render" "$env" "${common[@]}" --shading shrm --shrm "$tmp/p$p.shrm.json" \
            --compare "$tmp/$name-ref.exr" --json -o "$tmp/$name-p$p.exr" --label "P=$p" "${extra[@]}" \
            >"$tmp/$name-p$p.json"
        # Plain assignments, so that a field missing from render's summary stops the script.
        summary="$tmp/$name-p$p.json"
        epsilon="$(json_get "$summary" epsilon_achieved)"
        rel_error="$(json_get "$summary" metrics.rel_error)"
        psnr="$(json_get "$summary" metrics.psnr)"
        energy="$(awk -v e="$epsilon" 'BEGIN { printf "%.6f", 1 - e }')"
        json_row view="$name" p="$p" brdf_energy="$energy" rel_error="$rel_error" psnr="$psnr"
        table+=("$(printf '| %s | %s | %.4f | %.4f | %.2f |' "$name" "$p" "$energy" "$rel_error" "$psnr")")
        items+=(--panel-item "P=$p=$tmp/$name-p$p.exr")
    done
done

{
    echo "## Microfacet SHRMs against the exact image (Ramamoorthi & Hanrahan 2002, Fig. 7)"
    echo
    echo "Simplified microfacet BRDF (eq. 11) with σ = 0.2, cosine folded into ρ̂, global SHRMs with"
    echo "F_B = 30 and P = 0…3 from \`prefilter --order 30,P --global\`, rendered on a sphere under"
    echo "\`$(basename "$env")\` at ${res}x${res} for two distant views (camera 40 units away, 3.2° field: one"
    echo "view direction per image, as the paper's); the exact image sums L ρ cos θ_i over every"
    echo "probe texel at each pixel. \"BRDF energy\" is 1 − ε, the fraction of ρ̂'s energy the P"
    echo "terms keep (the paper's percentages, its conservative accuracy estimate). Regenerate:"
    echo "\`scripts/reproduce-fig7.sh\`."
    echo
    echo "| view | P | BRDF energy 1 − ε | relative L² error vs exact | PSNR (dB) |"
    echo "| --- | ---: | ---: | ---: | ---: |"
    printf '%s\n' "${table[@]}"
    echo
    echo "![P = 0…3 and the exact image, side view](../render-fig7-side.png)"
    echo
    echo "![P = 0…3 and the exact image, top view](../render-fig7-top.png)"
} >"$docs/results/render-fig7.md"
