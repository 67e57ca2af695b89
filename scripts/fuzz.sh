#!/usr/bin/env bash
# Runs the fuzz harness (tests/fuzz/) longer than CI does, with a random seed, and writes the
# tally to docs/results/fuzz.md: per parser the library and binary runs and the findings.
# Usage: scripts/fuzz.sh [SECONDS]   (default 600; FUZZ_SEED=N to repeat a run)
# Inputs behind findings are kept in target/fuzz-findings/; the exit status is 1 if any.
# Knobs (scripts/README.md): PRTKIT_RESULTS, PRTKIT_SMALL=1 (30 s). The harness is a test, built
# by cargo: with PRTKIT_BIN the script says so and stops.
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
if [ -n "${PRTKIT_BIN:-}" ]; then
    echo "fuzz: not run: the harness is cargo test --test fuzz, which builds (PRTKIT_BIN says not to)" >&2
    exit 0
fi
seconds=${1:-600}
if [ "$small" = 1 ]; then seconds=${1:-30}; fi
seed=${FUZZ_SEED:-$(od -An -N8 -tu8 /dev/urandom | tr -d ' ')}
echo "fuzz: building the harness and the binaries (cargo's progress follows)..." >&2
CARGO_BUILD_JOBS=${CARGO_BUILD_JOBS:-1} cargo test --release --test fuzz --no-run >&2
echo "fuzz: seed $seed, $seconds s" >&2
report=$(mktemp)
trap 'rm -f "$report"' EXIT
FUZZ_SECONDS=$seconds FUZZ_SEED=$seed FUZZ_REPORT=$report \
    cargo test --release --test fuzz fuzz_long -- --ignored --nocapture 2>&1 \
    | grep -E '^fuzz |^  [a-z]+ ' >&2 || true
if [ ! -s "$report" ]; then
    echo "fuzz: the harness did not finish (run: cargo test --release --test fuzz fuzz_long -- --ignored --nocapture)" >&2
    exit 2
fi
cp "$report" "$docs/results/fuzz.md"
cat "$docs/results/fuzz.md" >&2
if ! grep -q '^No findings' "$docs/results/fuzz.md"; then
    echo "fuzz: findings (inputs in target/fuzz-findings/)" >&2
    exit 1
fi
exit 0
