#!/usr/bin/env bash
# Mahajan, Tseng & Ramamoorthi 2008, Fig. 6: a Phong s = 30 sphere under a light probe,
# relit with K = 4, 12 and 75 hemisphere terms of the in-out factorization, next to the
# reference (direct integration over every probe texel). Prints one JSON line per K,
# {"k", "energy", "rel_error", "psnr", "seconds", "reference_seconds"}; writes
# docs/render-fig6.png and docs/results/render.md. Times are render's own (`--json` "seconds":
# projection and frame, after loading), the reference's from the same run.
# Usage: scripts/reproduce-fig6.sh [RES]   (default 160: 160x160 pixels)
# Knobs (scripts/README.md): PRTKIT_BIN, PRTKIT_RESULTS, PRTKIT_SMALL=1 (32x32 pixels, 32x32
# factor cells, 2x2 lighting samples per cell).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
res="${1:-160}" cells=64 cell_samples=3
if [ "$small" = 1 ]; then res=32 cells=32 cell_samples=2; fi
build --bin render --bin sample-shader --bin factor-brdf
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
source scripts/lib/light-probe.sh
common=(--brdf phong:s=30 --res "${res}x${res}" --eye 0,-4,0.8 --fov 30 -q)
"$bin/render" "$env" "${common[@]}" --shading reference -o "$tmp/ref.exr" --json >"$tmp/ref.json"
reference_seconds="$(json_get "$tmp/ref.json" seconds)"
# factor-brdf: cells x cells (cos θ, φ) cells per hemisphere, cosine folded in, the leading 75
# factors stored for render; cell_samples² lighting samples per cell.
"$bin/factor-brdf" phong:s=30 --resolution "$cells" --cosine --terms 75 --factors "$tmp/p30.exr" \
    -o "$tmp/p30.json" -q
fac=(--shading factored --bright off --factors "$tmp/p30.json" --cell-samples "$cell_samples"
    --compare "$tmp/ref.exr" --json)
table=()
for k in 4 12 75; do
    extra=()
    if [ "$k" = 75 ]; then
        extra=(--exposure 1 --panel "$docs/render-fig6.png" --panel-item "reference=$tmp/ref.exr"
            --panel-item "K=4=$tmp/k4.exr" --panel-item "K=12=$tmp/k12.exr")
    fi
    "$bin/render" "$env" "${common[@]}" "${fac[@]}" -K "$k" -o "$tmp/k$k.exr" "${extra[@]}" >"$tmp/k$k.json"
    # render's summary: "terms": [K, energy kept], the comparison under "metrics". Plain
    # assignments, so that a missing field stops the script (set -e).
    summary="$tmp/k$k.json"
    kept="$(json_get "$summary" terms.0)"
    energy="$(json_get "$summary" terms.1)"
    rel_error="$(json_get "$summary" metrics.rel_error)"
    psnr="$(json_get "$summary" metrics.psnr)"
    seconds="$(json_get "$summary" seconds)"
    json_row k="$kept" energy="$energy" rel_error="$rel_error" psnr="$psnr" seconds="$seconds" \
        reference_seconds="$reference_seconds"
    ratio="$(awk -v a="$seconds" -v b="$reference_seconds" 'BEGIN { printf "%.2f", a / b }')"
    table+=("$(printf '| %s | %.4f | %.4f | %.2f | %.2f | %s |' "$kept" "$energy" "$rel_error" "$psnr" "$seconds" "$ratio")")
done

{
    echo "## Factored relighting (Mahajan et al. 2008, Fig. 6)"
    echo
    echo "Phong s = 30 sphere under \`$(basename "$env")\`, ${res}x${res} pixels; in-out factorization by"
    echo "\`factor-brdf --factors\` on the hemisphere (${cells}x${cells} cells in cos θ, φ; cosine folded into g_k),"
    echo "read by \`render --factors\`, lighting projected onto the"
    echo "factors with ${cell_samples}x${cell_samples} samples per cell; error over the sphere's pixels against the reference (sum"
    echo "over every probe texel of L ρ cos θ_i). Time: render's own (projection and frame), against the"
    echo "reference's $(printf '%.2f' "$reference_seconds") s in the same run. Regenerate: \`scripts/reproduce-fig6.sh\`."
    echo
    echo "| K | energy kept | relative L² error | PSNR (dB) | time (s) | × reference time |"
    echo "| ---: | ---: | ---: | ---: | ---: | ---: |"
    printf '%s\n' "${table[@]}"
    echo
    echo "![reference, K = 4, 12, 75](../render-fig6.png)"
} >"$docs/results/render.md"
