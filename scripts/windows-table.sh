#!/usr/bin/env bash
# Each window's error (docs/results/windows.md): sh-project reconstructions against the map, and
# default prefilter reflection maps against the angular reference, on every shared light probe
# and the demo sky. The references are ring-free-table.sh's, cached in target/ring-free/ (about
# 1.5 minutes here when they are; computed and cached when not).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/lib/ring-free-probes.sh
build_ring_free windows
target/release/examples/windows docs/results/windows.md "$cache" "${probes[@]}"
