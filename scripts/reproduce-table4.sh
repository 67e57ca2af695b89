#!/usr/bin/env bash
# R&H 2002 Table 4 (Phong): angular vs frequency prefiltering, measured in one run. Prints one
# JSON line per exponent on stdout and writes docs/results/prefilter-table4.md.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo bench --quiet --bench prefilter_tables -- --table 4 --out docs/results/prefilter-table4.md
