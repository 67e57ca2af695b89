#!/usr/bin/env bash
# Filament's cmgen (--ibl-ld) against `ibl` on the same map at the same sizes: times, ratio and
# each one's error per level against the same angular reference, into docs/results/peers.md.
# Not part of CI. Installs cmgen from the distribution (libfilament-tools) when it can; skips
# with a message when it cannot. The work is done in Rust (examples/peers.rs).
# Usage: scripts/bench-peers.sh [MAP, default ../shared/testdata/envmaps/grace_latlong.exr] [SAMPLES]
# Knobs (scripts/README.md): PRTKIT_BIN, PRTKIT_RESULTS, PRTKIT_SMALL=1 (16 samples).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
map="${1:-../shared/testdata/envmaps/grace_latlong.exr}"
samples="${2:-256}"
if [ "$small" = 1 ]; then samples="${2:-16}"; fi
if ! command -v cmgen >/dev/null 2>&1; then
    if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
        DEBIAN_FRONTEND=noninteractive apt-get install -y -q libfilament-tools >/dev/null 2>&1 || true
    fi
fi
if ! command -v cmgen >/dev/null 2>&1; then
    echo "bench-peers: skipped: cmgen is not installed and libfilament-tools could not be had" >&2
    exit 0
fi
if [ ! -f "$map" ]; then
    echo "bench-peers: skipped: $map is absent" >&2
    exit 0
fi
build --bin ibl --example peers
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$bin/examples/peers" "$(command -v cmgen)" "$bin/ibl" "$map" "$work" "$docs/results/peers.md" "$samples"
echo "wrote $docs/results/peers.md" >&2
