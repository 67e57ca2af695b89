#!/usr/bin/env bash
# transfer's visibility rays through prtkit's BVH and through Intel Embree 3, side by side on the
# same rays (examples/visibility_vs_embree.rs): the shadowed bake's rays (1 024 per vertex) from
# every 10th vertex of scripts/lib/bowl-scene.sh's bowl holding a ball (about 100 000 vertices),
# best of 3 alternating passes on 1 and 2 threads. Writes docs/results/visibility.md and one JSON
# row per figure on stdout. Embree is a peer loaded at run time: without Debian's libembree-dev
# the script says so and exits 2 (install it with `apt-get install libembree-dev`).
# Knobs (scripts/README.md): PRTKIT_BIN, PRTKIT_RESULTS, PRTKIT_SMALL=1 (a 650-vertex scene,
# 64 rays, every vertex, one pass).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
source scripts/lib/bowl-scene.sh
rings=125 segments=400 rays=1024 stride=10 repeats=3
if [ "$small" = 1 ]; then rings=12 segments=24 rays=64 stride=1 repeats=1; fi
which="every ${stride}th vertex"
if [ "$stride" = 1 ]; then which="every vertex"; fi
build --example visibility_vs_embree
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
bowl_scene "$rings" "$segments" >"$tmp/scene.obj"
echo "visibility-vs-embree: $rays rays from $which, best of $repeats…" >&2
"$bin/examples/visibility_vs_embree" "$tmp/scene.obj" "$rays" "$stride" "$repeats" | tee "$tmp/rows.jsonl"

{
  echo "## Visibility rays: prtkit's BVH against Embree"
  echo
  echo "The rays of a shadowed \`transfer\` bake ($rays per vertex, stratified and cosine-weighted about the"
  echo "normal, from x + 10⁻⁴·diagonal·n) from $which of the bowl holding a ball that"
  echo "\`scripts/transfer-results.sh\` bakes, answered occluded or not by prtkit's BVH (\`Occluders\`: obvhs'"
  echo "8-wide compressed BVH, PLOC build, single precision) and by Intel Embree 3.13.5 (Debian's"
  echo "\`libembree-dev\`, \`rtcOccluded1\` on a high-quality static scene), the same rays in the same chunks on"
  echo "rayon pools of 1 and 2 threads, best of $repeats passes alternating between the two. One run of"
  echo "\`examples/visibility_vs_embree.rs\`; regenerate: \`scripts/visibility-vs-embree.sh\`."
  echo
  jq -r 'select(.check == "build") | "Scene: \(.vertices) vertices, \(.triangles) triangles. BVH build (one each): prtkit \(.prtkit_seconds * 1000 | round) ms (sequential), Embree \(.embree_seconds * 1000 | round) ms (its own threads)."' "$tmp/rows.jsonl"
  echo
  echo "| threads | rays | prtkit rays/s | Embree rays/s | prtkit / Embree | answers that differ | occluded |"
  echo "| ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
  jq -r 'select(.check == "trace") | "| \(.threads) | \(.rays) | \(.prtkit_rays_per_second / 1e6 * 100 | round / 100) M | \(.embree_rays_per_second / 1e6 * 100 | round / 100) M | \(.ratio * 1000 | round / 10) % | \(.differ) (\(.differ_fraction * 1e7 | round / 10) per million) | \(.occluded_fraction * 1000 | round / 10) % |"' "$tmp/rows.jsonl"
  echo
  echo "The answers that differ are single-precision ties: rays that graze an edge or a silhouette,"
  echo "where the two intersection tests round differently."
} >"$docs/results/visibility.md"
echo "visibility-vs-embree: wrote $docs/results/visibility.md" >&2
