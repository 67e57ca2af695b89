#!/usr/bin/env bash
# Measures every level of the `ibl` bake on the shared light probes against the angular integral
# and writes the table into docs/results/ibl-accuracy.md (the work is done in Rust:
# examples/ibl_accuracy.rs). Usage: scripts/ibl-accuracy.sh [SAMPLES per level, default 256]
# Skips with a message without the shared light probes.
# Knobs (scripts/README.md): PRTKIT_BIN, PRTKIT_RESULTS, PRTKIT_SMALL=1 (16 samples per level).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
samples="${1:-256}"
if [ "$small" = 1 ]; then samples="${1:-16}"; fi
require_shared envmaps
build --example ibl_accuracy
"$bin/examples/ibl_accuracy" "$docs/results/ibl-accuracy.md" "$samples"
echo "wrote $docs/results/ibl-accuracy.md" >&2
