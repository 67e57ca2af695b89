#!/usr/bin/env bash
# The README's factored relighting example (demo sky, Phong s = 30, K = 75 in-out terms, 128²)
# with the bright sources apart (render's default, --bright auto) and with the paper's method
# (--bright off), each against the ground truth: writes docs/results/render-bright.md.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet --bin sample-shader --bin factor-brdf --bin render
bin=target/release
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
"$bin/sample-shader" testdata/shaders/sky.sl --latlong 512x256 -o "$tmp/sky.exr" -q
"$bin/factor-brdf" phong:s=30 --terms 75 --factors "$tmp/p30.exr" -o "$tmp/p30.json" -q
"$bin/render" "$tmp/sky.exr" --brdf phong:s=30 --res 128x128 -o "$tmp/ref.exr" -q
measure() {
  "$bin/render" "$tmp/sky.exr" --brdf phong:s=30 --res 128x128 --shading factored \
      --factors "$tmp/p30.json" -K 75 --bright "$1" --compare "$tmp/ref.exr" -o "$tmp/k75-$1.exr" 2>&1 \
    | sed -n 's/^render: vs .*ref\.exr: //p'
}
off="$(measure off)"
auto="$(measure auto)"
out=docs/results/render-bright.md
{
  echo "## Factored relighting with bright sources apart"
  echo
  echo "Written by \`scripts/factored-bright.sh\` ($("$bin/render" --version)): the README's example"
  echo "(\`sample-shader\` sky 512×256, \`factor-brdf phong:s=30 --terms 75\`, 40² hemisphere cells,"
  echo "\`render --res 128x128 --shading factored -K 75\`) against the ground truth."
  echo
  echo "| \`--bright\` | against the reference |"
  echo "| --- | --- |"
  echo "| \`off\` (the paper's method) | $off |"
  echo "| \`auto\` (default: the sun's texels shaded exactly) | $auto |"
} > "$out"
echo "wrote $out" >&2
