#!/usr/bin/env bash
# The README's factored relighting example (demo sky, Phong s = 30, K = 75 in-out terms, 128²)
# with the bright sources apart (render's default, --bright auto) and with the paper's method
# (--bright off), each against the ground truth: writes docs/results/render-bright.md and prints
# one JSON line per mode, {"bright", "rel_error", "p99_texel_error", "max_texel_error",
# "negative_fraction", "psnr", "pixels"}.
# Knobs (scripts/README.md): PRTKIT_BIN, PRTKIT_RESULTS, PRTKIT_SMALL=1 (sky 128x64, 24² cells,
# 32x32 pixels).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
sky=512x256 cells=40 res=128
if [ "$small" = 1 ]; then sky=128x64 cells=24 res=32; fi
build --bin sample-shader --bin factor-brdf --bin render
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
"$bin/sample-shader" testdata/shaders/sky.sl --latlong "$sky" -o "$tmp/sky.exr" -q
"$bin/factor-brdf" phong:s=30 --terms 75 --resolution "$cells" --factors "$tmp/p30.exr" -o "$tmp/p30.json" -q
"$bin/render" "$tmp/sky.exr" --brdf phong:s=30 --res "${res}x${res}" -o "$tmp/ref.exr" -q
# measure MODE: prints the JSON row of `--bright MODE` and sets $measured to its table cell.
measure() {
  local summary="$tmp/k75-$1.json" rel p99 max x y negative psnr pixels
  "$bin/render" "$tmp/sky.exr" --brdf phong:s=30 --res "${res}x${res}" --shading factored \
      --factors "$tmp/p30.json" -K 75 --bright "$1" --compare "$tmp/ref.exr" -o "$tmp/k75-$1.exr" \
      --json -q >"$summary"
  rel="$(json_get "$summary" metrics.rel_error)"
  p99="$(json_get "$summary" metrics.p99_texel_error)"
  max="$(json_get "$summary" metrics.max_texel_error)"
  x="$(json_get "$summary" metrics.worst_texel.0)"
  y="$(json_get "$summary" metrics.worst_texel.1)"
  negative="$(json_get "$summary" metrics.negative_fraction)"
  psnr="$(json_get "$summary" metrics.psnr)"
  pixels="$(json_get "$summary" metrics.pixels)"
  json_row bright="$1" rel_error="$rel" p99_texel_error="$p99" max_texel_error="$max" \
      negative_fraction="$negative" psnr="$psnr" pixels="$pixels"
  # render's own sentence for a comparison (its stderr without -q), from the same numbers.
  measured="$(awk -v r="$rel" -v p="$p99" -v m="$max" -v x="$x" -v y="$y" -v n="$negative" -v s="$psnr" -v px="$pixels" \
      'BEGIN { printf "rel error %.2f %%, per texel p99 %.2f %% and max %.2f %% at (%d, %d), %.2f %% negative texels, PSNR %.2f dB over %d pixels", 100 * r, 100 * p, 100 * m, x, y, 100 * n, s, px }')"
}
measure off
off="$measured"
measure auto
auto="$measured"
out="$docs/results/render-bright.md"
{
  echo "## Factored relighting with bright sources apart"
  echo
  echo "Written by \`scripts/factored-bright.sh\` ($("$bin/render" --version)): the README's example"
  echo "(\`sample-shader\` sky ${sky/x/×}, \`factor-brdf phong:s=30 --terms 75\`, ${cells}² hemisphere cells,"
  echo "\`render --res ${res}x${res} --shading factored -K 75\`) against the ground truth."
  echo
  echo "| \`--bright\` | against the reference |"
  echo "| --- | --- |"
  echo "| \`off\` (the paper's method) | $off |"
  echo "| \`auto\` (default: the sun's texels shaded exactly) | $auto |"
} > "$out"
echo "wrote $out" >&2
