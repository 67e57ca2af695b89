#!/usr/bin/env bash
# How `ibl` scales with the input (512×256 → 16384×8192) and the faces (128² → 4096²), with and
# without its measurement, Filament's cmgen beside it where it runs, and the largest inputs under a
# 4 GiB address space, into docs/results/ibl-scaling.md. Not part of CI (minutes, and 2.6 GB of
# inputs in a temporary directory). The work is done in Rust (examples/ibl_scaling.rs); timing by
# /usr/bin/time (Debian's `time`). cmgen (libfilament-tools) is used when installed.
# Usage: scripts/ibl-scaling.sh [MAP, default ../shared/testdata/envmaps/grace_latlong.exr]
# Knobs (scripts/README.md): PRTKIT_BIN, PRTKIT_RESULTS, PRTKIT_SMALL=1 (two tiny inputs).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
map="${1:-../shared/testdata/envmaps/grace_latlong.exr}"
if [ ! -f "$map" ]; then
    echo "ibl-scaling: skipped: $map is absent" >&2
    exit 0
fi
if [ ! -x /usr/bin/time ]; then
    echo "ibl-scaling: skipped: /usr/bin/time is absent (Debian: apt-get install time)" >&2
    exit 0
fi
cmgen="$(command -v cmgen || echo -)"
build --bin ibl --example ibl_scaling
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
flags=()
if [ "$small" = 1 ]; then flags=(--small); fi
"$bin/examples/ibl_scaling" "$bin/ibl" "$cmgen" "$map" "$work" "$docs/results/ibl-scaling.md" "${flags[@]}"
echo "wrote $docs/results/ibl-scaling.md" >&2
