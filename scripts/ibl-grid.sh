#!/usr/bin/env bash
# The `render --shading ibl --grid` errors on shared probes (bake against its own integrals and
# against the rendering equation), written into docs/results/ibl-grid.md (the work is done in
# Rust: examples/ibl_grid.rs). About a minute on 2 cores. Usage: scripts/ibl-grid.sh
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_BUILD_JOBS="${CARGO_BUILD_JOBS:-1}"
cargo run --release --quiet --example ibl_grid -- docs/results/ibl-grid.md
echo "wrote docs/results/ibl-grid.md"
