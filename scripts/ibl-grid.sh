#!/usr/bin/env bash
# The `render --shading ibl --grid` errors on shared probes (bake against its own integrals and
# against the rendering equation), written into docs/results/ibl-grid.md (the work is done in
# Rust: examples/ibl_grid.rs). About a minute on 2 cores. Usage: scripts/ibl-grid.sh
# Skips with a message without the shared light probes.
# Knobs (scripts/README.md): PRTKIT_BIN, PRTKIT_RESULTS (the example has no smaller size).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
require_shared envmaps
build --example ibl_grid
"$bin/examples/ibl_grid" "$docs/results/ibl-grid.md"
echo "wrote $docs/results/ibl-grid.md" >&2
