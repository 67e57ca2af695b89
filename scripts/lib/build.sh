# Sourced by scripts/demo.sh and .ci/run: `narrated_build CMD…` runs a build that may take minutes.
# On a terminal cargo draws its own progress. Elsewhere (CI logs, a pipe, `| tee`) cargo prints a
# line per crate but nothing while one large crate compiles, for minutes at a time: say every
# 20 s that the build is still going, so it never looks hung.
narrated_build() {
  if [ -t 2 ]; then
    "$@"
    return
  fi
  "$@" &
  local pid=$! start=$SECONDS next=$((SECONDS + 20))
  while kill -0 "$pid" 2>/dev/null; do
    sleep 1
    if [ "$SECONDS" -ge "$next" ]; then
      printf '   ... still building (%d s)\n' "$((SECONDS - start))" >&2
      next=$((SECONDS + 20))
    fi
  done
  wait "$pid"
}
