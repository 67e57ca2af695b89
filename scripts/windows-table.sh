#!/usr/bin/env bash
# Each window's error (docs/results/windows.md): sh-project reconstructions against the map, and
# default prefilter reflection maps against the angular reference, on every shared light probe
# and the demo sky. The references are ring-free-table.sh's, cached in target/ring-free/ (about
# 1.5 minutes here when they are; computed and cached when not).
# Knobs (scripts/README.md): PRTKIT_BIN, PRTKIT_RESULTS (the example has no smaller size).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
source scripts/lib/ring-free-probes.sh
build_ring_free windows
"$bin/examples/windows" "$docs/results/windows.md" "$cache" "${probes[@]}"
