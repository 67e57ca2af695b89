#!/usr/bin/env bash
# The ring-free table (docs/results/ring-free.md): default prefilter reflection maps on every
# shared light probe and the demo sky against the angular reference. The references take most of
# the time (about 30 minutes on 2 cores the first time); they are cached in target/ring-free/.
set -euo pipefail
cd "$(dirname "$0")/.."
probes=../shared/testdata/envmaps
cache=target/ring-free
mkdir -p "$cache"
echo "building (release)…" >&2
cargo build --release --bins --example ring_free
if [ ! -f "$cache/sky.exr" ]; then
  target/release/sample-shader testdata/shaders/sky.sl --latlong 512x256 --tolerance 0.05 -o "$cache/sky.exr" -q
fi
target/release/examples/ring_free docs/results/ring-free.md "$cache" \
  "$probes/grace_latlong.exr" \
  "$probes/dxsdk_cubes/grace" "$probes/dxsdk_cubes/rnl" "$probes/dxsdk_cubes/stpeters" "$probes/dxsdk_cubes/galileo" \
  "$probes/uffizi_ict_latlong_256x128.hdr" \
  "$cache/sky.exr"
