#!/usr/bin/env bash
# The ring-free table (docs/results/ring-free.md): default prefilter reflection maps on every
# shared light probe and the demo sky against the angular reference. The references take most of
# the time (about 30 minutes on 2 cores the first time); they are cached in target/ring-free/.
# Knobs (scripts/README.md): PRTKIT_BIN, PRTKIT_RESULTS (the example has no smaller size).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
source scripts/lib/ring-free-probes.sh
build_ring_free ring_free
"$bin/examples/ring_free" "$docs/results/ring-free.md" "$cache" "${probes[@]}"
