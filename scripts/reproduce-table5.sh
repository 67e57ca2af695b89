#!/usr/bin/env bash
# R&H 2002 Table 5 (microfacet SHRMs and 100 reflection maps), measured in one run. Prints one
# JSON line per roughness on stdout and writes docs/results/prefilter-table5.md.
# ANGULAR_VIEWS=K times K of the 100 angular reflection maps (evenly spread over the view grid)
# and scales the time to 100 (default 20, so the script ends within 10 minutes; 100 times them all).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo bench --quiet --bench prefilter_tables -- --table 5 --angular-views "${ANGULAR_VIEWS:-20}" --out docs/results/prefilter-table5.md
