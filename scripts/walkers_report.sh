#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Runs walkers (64 agents, 600 frames, spawns, brush oracle) on every shared
# level and the arena sample at 6 and 40 m/s, with each narrow phase
# (METHODS, default "planes exact"), 3 runs each, and prints a
# Markdown table: the median of the runs' ns per agent-step (each itself a
# median over frames), refused moves, slide iterations per step and
# agent-frames inside a solid. Release build expected in ${BUILD:-build}.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD:-build}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "| level | method | m/s | ns per agent-step | refused moves | iterations mean | grounded | inside solid | fell out |"
echo "|---|---|---:|---:|---:|---:|---:|---:|---:|"
levels=(samples/arena)
[ -d ../shared/levels ] && for l in fan oa_dm1 oacmpdm5 oa_dm4 oa_dm5 oacmpctf3; do levels+=("../shared/levels/$l"); done
for level in "${levels[@]}"; do
  name=$(basename "$level")
  "$build/compiler/bspc" -q "$level.obj" -o "$tmp/$name.bspf"
  for method in ${METHODS:-planes exact}; do
  for speed in 6 40; do
    for run in 1 2 3; do
      "$build/samples/walkers" "$tmp/$name.bspf" --spawns "$level.spawns.txt" \
        --brushes "$level.brushes.txt" --speed "$speed" --method "$method" --json \
        > "$tmp/$name.$speed.$run.json"
    done
    python3 - "$tmp" "$name" "$speed" "$method" <<'PY'
import json, statistics, sys
tmp, name, speed, method = sys.argv[1:]
runs = [json.load(open(f"{tmp}/{name}.{speed}.{r}.json")) for r in (1, 2, 3)]
r = runs[0]
print(f"| {name} | {method} | {speed} | {statistics.median(x['ns_per_step'] for x in runs):.0f} | {r['refused_moves']} | "
      f"{r['iterations_mean']:.2f} | {r['grounded_fraction']:.2f} | {r['inside_solid']} | {r['fell_out']} |")
PY
  done
  done
done
