#!/usr/bin/env bash
# R&H 2002 Table 5 (microfacet SHRMs and 100 reflection maps), measured in one run. Prints one
# JSON line per roughness on stdout and writes docs/results/prefilter-table5.md.
# The angular reference computes all 100 reflection maps (about 15 minutes on 2 cores);
# ANGULAR_VIEWS=K times K of them (evenly spread over the view grid) and scales the time to 100,
# for a quick look.
# Knobs (scripts/README.md): PRTKIT_RESULTS; it is a benchmark, so with PRTKIT_BIN it only says so.
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
if ! can_bench "Table 5 (cargo bench --bench prefilter_tables)"; then exit 0; fi
cargo bench --quiet --bench prefilter_tables -- --table 5 --angular-views "${ANGULAR_VIEWS:-100}" \
    --out "$docs/results/prefilter-table5.md"
