# Sourced first by every script in scripts/ (not demo.sh): the knobs of scripts/README.md, written
# once. Moves to the repository's root (relative paths of the scripts are from there) and sets
#   docs     where results go: the repository's docs/, or $PRTKIT_RESULTS. Sections are written
#            into $docs/results/, pictures and results.md into $docs/ (so a section's links to
#            its pictures, ../NAME.png, hold in both).
#   small    1 when PRTKIT_SMALL=1: each script picks tiny sizes and finishes in seconds (the
#            tests run them so; the numbers are then a check, not a result to publish).
# and defines
#   build ARGS...      `cargo build --release ARGS` and bin=target/release; with PRTKIT_BIN=DIR
#                      no build at all, bin=DIR (the examples are then DIR/examples/NAME).
#   json_get FILE KEY  one value of a JSON document, pretty or compact (see below; needs jq,
#                      which .ci/run installs).
#   json_row K=V...    a compact JSON object on stdout, one line: a script's machine-readable row.
#   json_compact       JSON on stdin onto one line.
#   can_bench WHAT     whether `cargo bench` may run (not with PRTKIT_BIN); says what is left out.
#   require_shared DIR stops the script, saying why, when ../shared/testdata/DIR is absent.

# A script's own arguments are resolved before moving; PRTKIT_RESULTS is made absolute too.
caller_dir=$PWD
cd "$(dirname "$0")/.."
case "${PRTKIT_RESULTS:-}" in
  "") docs=docs ;;
  /*) docs=$PRTKIT_RESULTS ;;
  *) docs=$caller_dir/$PRTKIT_RESULTS ;;
esac
mkdir -p "$docs/results"
small=0
if [ "${PRTKIT_SMALL:-0}" = 1 ]; then small=1; fi
# Builds share the machine with other work: one job unless the caller says otherwise.
# Tables print numbers with a decimal point whatever the locale.
export LC_NUMERIC=C
export CARGO_BUILD_JOBS="${CARGO_BUILD_JOBS:-1}"
if ! command -v jq >/dev/null; then
  echo "$(basename "$0"): needs jq to read the stages' --json summaries (Debian: apt-get install jq)" >&2
  exit 2
fi

# build ARGS...: what the script runs, as cargo build's target selection (--bin NAME, --example
# NAME, --bins). With PRTKIT_BIN the binaries are taken as they are: the tests pass the ones cargo
# built for them, and a build inside `cargo test` would redo them with other features, for minutes.
build() {
  if [ -n "${PRTKIT_BIN:-}" ]; then
    bin=$PRTKIT_BIN
    case "$bin" in /*) ;; *) bin=$caller_dir/$bin ;; esac
  else
    echo "$(basename "$0"): building (cargo build --release $*)…" >&2
    cargo build --release --quiet "$@"
    bin=target/release
  fi
}

# json_get FILE KEY: prints the scalar at KEY in the JSON document FILE, KEY being the object keys
# and array indices from the top joined by dots (metrics.rel_error, terms.0); strings without their
# quotes. Fails, naming the key, when it is absent or not a scalar. jq reads the document, so its
# layout (the stages pretty-print --json) is theirs to change: a sed over one-line JSON broke
# reproduce-fig6.sh silently once.
json_get() {
  jq -er --arg key "$2" --arg file "$1" '
    getpath($key | split(".") | map(tonumber? // .)) as $v
    | if ($v | type) == "object" or ($v | type) == "array" or $v == null
      then error("json_get: \($file): no scalar at \"\($key)\"") else $v end' "$1"
}

# json_row K=V...: prints {"K":V,...} on one line. V is written as given when it is a JSON number
# (or true/false/null), else as a string (quoted; the values here hold no quotes or backslashes).
json_row() {
  local out="" sep="" kv k v
  for kv in "$@"; do
    k=${kv%%=*}
    v=${kv#*=}
    if ! [[ $v =~ ^-?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?$|^(true|false|null)$ ]]; then v="\"$v\""; fi
    out="$out$sep\"$k\":$v"
    sep=,
  done
  printf '{%s}\n' "$out"
}

# json_compact: JSON on stdin onto one line on stdout.
json_compact() {
  jq -c .
}

# can_bench NAME: whether this run may call `cargo bench` (which builds the benchmarks). Not with
# PRTKIT_BIN, whose point is that nothing is built; then it says what is left out.
can_bench() {
  if [ -n "${PRTKIT_BIN:-}" ]; then
    echo "$(basename "$0"): not measured: $1 (cargo bench builds; PRTKIT_BIN says not to)" >&2
    return 1
  fi
}

# require_shared SUBDIR: the script reads ../shared/testdata/SUBDIR; without it, it says so and
# stops with success (a checkout without the shared data has nothing to measure there).
require_shared() {
  if [ ! -d "../shared/testdata/$1" ]; then
    echo "$(basename "$0"): skipped: ../shared/testdata/$1 is absent" >&2
    exit 0
  fi
}
