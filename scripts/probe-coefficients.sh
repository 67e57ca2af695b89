#!/usr/bin/env bash
# Writes the order-2 SH coefficients of the shared light probes into docs/results/probes.md (the
# work is done in Rust: examples/probe_coefficients.rs). Skips with a message without them.
# Knobs (scripts/README.md): PRTKIT_BIN, PRTKIT_RESULTS (PRTKIT_SMALL changes nothing: it is quick).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
require_shared envmaps
build --example probe_coefficients
"$bin/examples/probe_coefficients" "$docs/results/probes.md"
