#!/usr/bin/env bash
# Measures every level of the `ibl` bake on the shared light probes against the angular integral
# and writes the table into docs/results/ibl-accuracy.md (the work is done in Rust:
# examples/ibl_accuracy.rs). Usage: scripts/ibl-accuracy.sh [SAMPLES per level, default 256]
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_BUILD_JOBS="${CARGO_BUILD_JOBS:-1}"
cargo run --release --quiet --example ibl_accuracy -- docs/results/ibl-accuracy.md "${1:-256}"
echo "wrote docs/results/ibl-accuracy.md"
