#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Compiles every shared level (3 runs, median stage times), then reports blob
# size, tree figures, open-and-verify time and broad-phase work per query as
# Markdown tables. Release build expected in ${BUILD:-build}.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD:-build}
shared=../shared/levels
[ -d "$shared" ] || { echo "level_report: $shared is absent" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for level in fan oa_dm1 oacmpdm5 oa_dm4 oa_dm5 oacmpctf3; do
  for run in 1 2 3; do
    "$build/compiler/bspc" -q "$shared/$level.obj" -o "$tmp/$level.bspf" \
      --stats-json "$tmp/$level.$run.json" "$@"
  done
  "$build/bench/bspf_level_bench" "$tmp/$level.bspf" --repeats 5 > "$tmp/$level.bench.json"
done
python3 - "$tmp" <<'PY'
import json, statistics, sys
tmp = sys.argv[1]
levels = ["fan", "oa_dm1", "oacmpdm5", "oa_dm4", "oa_dm5", "oacmpctf3"]
print("| level | triangles in / kept | import ms | clean ms | build ms | planes ms | write ms | blob KiB | bytes/tri | open+verify ms |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
rows = []
for l in levels:
    runs = [json.load(open(f"{tmp}/{l}.{r}.json")) for r in (1, 2, 3)]
    b = json.load(open(f"{tmp}/{l}.bench.json"))
    med = lambda k: statistics.median(r["seconds"][k] for r in runs) * 1000
    s = runs[0]
    print(f"| {l} | {s['clean']['input_triangles']} / {s['triangles']} | {med('import'):.1f} | {med('clean'):.1f} | "
          f"{med('build_tree'):.1f} | {med('planes'):.1f} | {med('write'):.1f} | {s['output_bytes']/1024:.0f} | "
          f"{s['tree']['bytes_per_triangle']:.0f} | {b['open_ms_median']:.2f} |")
    rows.append((l, s, b))
print()
print("| level | nodes | leaves | depth max / mean | tris per leaf max / mean | refs per tri | leaves/query | candidates/query | ns/query |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
for l, s, b in rows:
    t = s["tree"]
    print(f"| {l} | {t['nodes']} | {t['leaves']} | {t['depth_max']} / {t['depth_mean']:.1f} | "
          f"{t['triangles_per_leaf_max']} / {t['triangles_per_leaf_mean']:.1f} | {t['references_per_triangle']:.2f} | "
          f"{b['leaves_mean']:.1f} | {b['candidates_mean']:.1f} | {b['ns_per_query_median']:.0f} |")
PY
