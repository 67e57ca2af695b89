#!/usr/bin/env bash
# CI for the viewer: installs what the browser tests need on a clean Debian machine (Chromium,
# the npm packages pinned in viewer/package-lock.json) and runs them against prtkit's binaries.
#   viewer/ci.sh [BIN_DIR]        (default target/release, relative to the repository root)
# The last line is "N passed, M failed"; the exit status is non-zero when anything failed.
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/.." && pwd)"
bin="${1:-target/release}"
case "$bin" in /*) ;; *) bin="$repo/$bin" ;; esac
start=$(date +%s)
fail() { echo "viewer ci: $*" >&2; echo "0 passed, 1 failed"; exit 1; }

command -v node >/dev/null 2>&1 || fail "node is missing (Node 20 or later)"
command -v npm >/dev/null 2>&1 || fail "npm is missing"
chromium="${CHROMIUM:-/usr/bin/chromium}"
if [ ! -x "$chromium" ]; then
  echo "viewer ci: installing chromium (apt)" >&2
  export DEBIAN_FRONTEND=noninteractive
  { apt-get update -qq && apt-get install -y -qq chromium >/dev/null; } || fail "could not install chromium"
fi
[ -x "$chromium" ] || fail "$chromium missing after install"
echo "viewer ci: $("$chromium" --version 2>/dev/null | head -1)" >&2
echo "viewer ci: npm ci in viewer/" >&2
(cd "$here" && npm ci --no-audit --no-fund --loglevel=error >/dev/null) || fail "npm ci failed"
installed=$(date +%s)

CHROMIUM="$chromium" node "$here/test/run.mjs" "$bin"
status=$?
end=$(date +%s)
echo "viewer ci: installs $((installed - start)) s, tests $((end - installed)) s" >&2
# run.mjs prints "N passed, M failed" last; if it died before that, say so in the same form.
if [ $status -gt 1 ]; then echo "0 passed, 1 failed"; fi
exit $status
