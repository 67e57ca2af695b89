#!/usr/bin/env bash
# Validates KTX 2.0 files with the npm package ktx-parse (installed into a temporary directory)
# and the layout checks of scripts/check-ktx2.mjs. One line per file; exit 1 if any file fails,
# 2 on a usage or setup error.
#   scripts/check-ktx2.sh out/specular.ktx2 out/dfg.ktx2
set -euo pipefail
if [ $# -lt 1 ]; then
  echo "usage: scripts/check-ktx2.sh FILE.ktx2..." >&2
  exit 2
fi
for tool in node npm; do
  command -v "$tool" >/dev/null || { echo "check-ktx2: $tool is not installed" >&2; exit 2; }
done
here=$(cd "$(dirname "$0")" && pwd)
files=()
for f in "$@"; do
  [ -f "$f" ] || { echo "check-ktx2: $f: no such file" >&2; exit 2; }
  files+=("$(cd "$(dirname "$f")" && pwd)/$(basename "$f")")
done
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
if ! (cd "$dir" && npm init -y >/dev/null 2>&1 && npm install --silent --no-audit --no-fund ktx-parse@2 >/dev/null 2>&1); then
  echo "check-ktx2: could not install ktx-parse with npm" >&2
  exit 2
fi
cp "$here/check-ktx2.mjs" "$dir/"
node "$dir/check-ktx2.mjs" "${files[@]}"
