#!/usr/bin/env bash
# Measures sh-project's decode and projection time and the speed-up over the naive projection,
# and writes docs/results/sh-project.md. Usage: scripts/bench-sh-project.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo bench --bench sh_project -- --out docs/results/sh-project.md
