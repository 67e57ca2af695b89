#!/usr/bin/env bash
# Opens an `ibl` bake in the browser viewer (viewer/README.md): serves the repository and DIR on
# 127.0.0.1 and prints the URL to open.
#   scripts/view.sh DIR [PORT]     DIR holds ibl.json (the -o of `ibl`); PORT defaults to 8333
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
if [ $# -lt 1 ] || [ ! -f "$1/ibl.json" ]; then
  echo "usage: scripts/view.sh DIR [PORT]   (DIR: an ibl output folder holding ibl.json)" >&2
  exit 2
fi
dir="$(cd "$1" && pwd)"
if [ ! -d "$repo/viewer/node_modules/three" ]; then
  echo "view: installing the viewer's npm packages (npm ci in viewer/)" >&2
  (cd "$repo/viewer" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
fi
exec node "$repo/viewer/serve.mjs" --bake "$dir" --port "${2:-8333}"
