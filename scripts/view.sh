#!/usr/bin/env bash
# Opens a prtkit output in the browser viewer (viewer/README.md): serves the repository and the
# output's folder on 127.0.0.1 and prints the URL to open.
#   scripts/view.sh DIR [PORT]          DIR holds ibl.json (the -o of `ibl`)
#   scripts/view.sh FILE.json [PORT]    sh-project's prtkit.sh document (mode=irradiance) or
#                                       prefilter's prtkit.shrm document (mode=shrm; its EXR beside it)
#   scripts/view.sh FILE.glb SH.json [PORT]   a `transfer --glb` bake relit by sh-project's SH of
#                                       the map (mode=prt; SH.json beside the .glb or under the repository)
# PORT defaults to 8333.
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
usage() { echo "usage: scripts/view.sh DIR|FILE.json [PORT] | FILE.glb SH.json [PORT]   (DIR: an ibl output folder holding ibl.json; FILE.json: a prtkit.sh or prtkit.shrm document; FILE.glb: a transfer bake, SH.json: sh-project of the map)" >&2; exit 2; }
[ $# -ge 1 ] || usage
port="${2:-8333}"
query=""
if [ -f "$1" ] && [ "${1##*.}" = glb ]; then
  [ $# -ge 2 ] && [ -f "$2" ] || usage
  port="${3:-8333}"
  dir="$(cd "$(dirname "$1")" && pwd)"
  sh_dir="$(cd "$(dirname "$2")" && pwd)"
  case "$sh_dir/" in
    "$dir/") sh_url="/bake/$(basename "$2")" ;;
    "$repo"/*) sh_url="${sh_dir#"$repo"}/$(basename "$2")" ;;
    *) echo "view: $2 must be beside $1 or under the repository (the server reaches only those)" >&2; exit 2 ;;
  esac
  query="?mode=prt&glb=/bake/$(basename "$1")&sh=$sh_url"
elif [ -d "$1" ]; then
  [ -f "$1/ibl.json" ] || usage
  dir="$(cd "$1" && pwd)"
  query="?ibl=/bake/"
elif [ -f "$1" ]; then
  dir="$(cd "$(dirname "$1")" && pwd)"
  name="$(basename "$1")"
  format="$(grep -o '"format": *"[^"]*"' "$1" | head -1 | sed 's/.*"\([^"]*\)"$/\1/')"
  case "$format" in
    prtkit.sh) query="?mode=irradiance&sh=/bake/$name" ;;
    prtkit.shrm) query="?mode=shrm&shrm=/bake/$name" ;;
    *) echo "view: $1 is a '$format' document; give a prtkit.sh or prtkit.shrm document, or an ibl folder" >&2; exit 2 ;;
  esac
else
  usage
fi
if [ ! -d "$repo/viewer/node_modules/three" ]; then
  echo "view: installing the viewer's npm packages (npm ci in viewer/)" >&2
  (cd "$repo/viewer" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
fi
exec node "$repo/viewer/serve.mjs" --bake "$dir" --port "$port" --query "$query"
