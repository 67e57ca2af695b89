#!/usr/bin/env bash
# Regenerates every measured number in docs/: runs each benchmark and reproduction script (each
# writes its section into docs/results/), then assembles docs/results.md from the sections.
#   scripts/update-results.sh            # run everything (about an hour on 2 cores), assemble
#   scripts/update-results.sh --assemble # only assemble docs/results.md from the sections
# Knobs (scripts/README.md): all three are passed on to the scripts it runs; with PRTKIT_RESULTS
# the sections are read from, and results.md written into, that directory.
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
if [ "${1:-}" != "--assemble" ]; then
  scripts/bench-sh-project.sh
  scripts/probe-coefficients.sh
  scripts/reproduce-table4.sh
  scripts/reproduce-table5.sh
  scripts/reproduce-terms.sh
  scripts/reproduce-normals-table.sh
  scripts/reproduce-shader-table.sh
  scripts/reproduce-fig6.sh
  scripts/factored-bright.sh
  scripts/transfer-results.sh
  scripts/reproduce-fig7.sh
  scripts/bench-render.sh
  scripts/ibl-accuracy.sh
  scripts/ibl-grid.sh
  scripts/ibl-scaling.sh
  scripts/ring-free-table.sh
  scripts/windows-table.sh
  scripts/fuzz.sh
  # scripts/bench-peers.sh (Filament's cmgen) and scripts/visibility-vs-embree.sh (Embree) are not
  # run here: their peers are packages to install.
fi
{
  echo "# Results"
  echo
  echo "Every number here was measured on the project's 2-core machine by the script named in its"
  echo "section; \`scripts/update-results.sh\` reruns them all and rebuilds this file from"
  echo "\`docs/results/*.md\`. Speeds are ratios measured in one run (the machine is shared and"
  echo "noisy); absolute times are for orientation only."
  echo
  for section in sh-project probes prefilter-table4 prefilter-table5 terms normals shader render render-bright render-fig7 render-bench transfer visibility ibl-accuracy ibl-grid ibl-scaling peers viewer ring-free windows fuzz; do
    f="$docs/results/$section.md"
    if [ -f "$f" ]; then
      # Sections link their figures relative to docs/results/; this file lives in docs/.
      sed -E -e 's#\]\(([A-Za-z0-9_.-]+\.(svg|png))\)#](results/\1)#g' -e 's#\]\(\.\./#](#g' "$f"
      echo
    fi
  done
} > "$docs/results.md"
echo "wrote $docs/results.md" >&2
