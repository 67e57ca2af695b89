#!/usr/bin/env bash
# Each window's error (docs/results/windows.md): sh-project reconstructions against the map, and
# default prefilter reflection maps against the angular reference, on every shared light probe
# and the demo sky. The references are ring-free-table.sh's, cached in target/ring-free/ (about
# 5 minutes here when they are; computed and cached when not).
set -euo pipefail
cd "$(dirname "$0")/.."
probes=../shared/testdata/envmaps
cache=target/ring-free
mkdir -p "$cache"
echo "building (release)…" >&2
cargo build --release --bins --example windows
if [ ! -f "$cache/sky.exr" ]; then
  target/release/sample-shader testdata/shaders/sky.sl --latlong 512x256 --tolerance 0.05 -o "$cache/sky.exr" -q
fi
target/release/examples/windows docs/results/windows.md "$cache" \
  "$probes/grace_latlong.exr" \
  "$probes/dxsdk_cubes/grace" "$probes/dxsdk_cubes/rnl" "$probes/dxsdk_cubes/stpeters" "$probes/dxsdk_cubes/galileo" \
  "$probes/uffizi_ict_latlong_256x128.hdr" \
  "$cache/sky.exr"
