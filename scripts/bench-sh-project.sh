#!/usr/bin/env bash
# Measures sh-project's decode and projection time and the speed-up over the naive projection,
# and writes docs/results/sh-project.md. Usage: scripts/bench-sh-project.sh
# Knobs (scripts/README.md): PRTKIT_RESULTS; it is a benchmark, so with PRTKIT_BIN it only says so.
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
if ! can_bench "the projection times (cargo bench --bench sh_project)"; then exit 0; fi
cargo bench --bench sh_project -- --out "$docs/results/sh-project.md"
