#!/usr/bin/env bash
# Writes the order-2 SH coefficients of the shared light probes into docs/results/probes.md.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo run --release --quiet --example probe_coefficients -- docs/results/probes.md
