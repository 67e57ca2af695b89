#!/usr/bin/env bash
# The ring-free table (docs/results/ring-free.md): default prefilter reflection maps on every
# shared light probe and the demo sky against the angular reference. The references take most of
# the time (about 30 minutes on 2 cores the first time); they are cached in target/ring-free/.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/lib/ring-free-probes.sh
build_ring_free ring_free
target/release/examples/ring_free docs/results/ring-free.md "$cache" "${probes[@]}"
