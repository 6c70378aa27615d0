#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Measures bspc's tree knobs one at a time around the defaults on the shared
# levels: tree size (references and bytes per triangle) against broad-phase
# work (leaves and candidate triangles per swept-ellipsoid query, and the
# median time per query). Prints a Markdown table. Release build expected in
# ${BUILD:-build}. Its queries are one frame's swept body each; the step's
# own (padded boxes kept for many frames) are measured with the walkers
# (docs/tree-tuning.md, "Query reach 6 m").
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD:-build}
levels=${LEVELS:-"oa_dm1 oa_dm5 oacmpctf3"}
shared=../shared/levels
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

variants=(
  ""
  "--max-leaf-triangles 2" "--max-leaf-triangles 4" "--max-leaf-triangles 16"
  "--query-reach 1" "--query-reach 3" "--query-reach 12"
  "--split-weight 0.5" "--split-weight 1" "--split-weight 4" "--split-weight 8"
  "--balance-weight 0" "--balance-weight 2"
  "--candidates axis" "--candidates triangle"
)
echo "| options | level | build s | refs/tri | bytes/tri | depth max | leaves/query | candidates/query | ns/query |"
echo "|---|---|---:|---:|---:|---:|---:|---:|---:|"
for variant in "${variants[@]}"; do
  for level in $levels; do
    # shellcheck disable=SC2086
    "$build/compiler/bspc" -q "$shared/$level.obj" -o "$tmp/$level.bspf" \
      --stats-json "$tmp/$level.json" $variant
    q=$("$build/bench/bspf_level_bench" "$tmp/$level.bspf" --repeats 5)
    python3 - "$tmp/$level.json" "$q" "${variant:-defaults}" "$level" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); q = json.loads(sys.argv[2]); t = s["tree"]
print(f"| {sys.argv[3]} | {sys.argv[4]} | {s['seconds']['build_tree']:.2f} | "
      f"{t['references_per_triangle']:.2f} | {t['bytes_per_triangle']:.0f} | {t['depth_max']} | "
      f"{q['leaves_mean']:.1f} | {q['candidates_mean']:.1f} | {q['ns_per_query_median']:.0f} |")
PY
  done
done
