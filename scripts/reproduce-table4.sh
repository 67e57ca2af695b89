#!/usr/bin/env bash
# R&H 2002 Table 4 (Phong): angular vs frequency prefiltering, measured in one run. Prints one
# JSON line per exponent on stdout and writes docs/results/prefilter-table4.md.
# Knobs (scripts/README.md): PRTKIT_RESULTS; it is a benchmark, so with PRTKIT_BIN it only says so.
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
if ! can_bench "Table 4 (cargo bench --bench prefilter_tables)"; then exit 0; fi
cargo bench --quiet --bench prefilter_tables -- --table 4 --out "$docs/results/prefilter-table4.md"
