#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The performance table of the movement step, in one run, on the arena
# sample, the shared levels (when ../shared/levels exists) and the three
# generated detailed levels (scripts/make_detailed_levels.py: terrain,
# curved_room, cad_building, generated into a temporary folder). Each level is
# compiled with bspc; then, for each method and speed:
#   - walkers (64 agents from the spawns, 600 frames, --json, 3 runs): the
#     median of the runs' ns per agent-step, refused moves, and agent-frames
#     inside a solid where a brushes file exists;
#   - bspf_replay_bench (the same crowd recorded, its steps replayed with
#     stepBody, 5 timed replays): ns per step, tree queries per step,
#     candidates per query (mean, p90), triangles whose box overlaps the swept
#     body's box, the ratio of the two, leaves and references per triangle;
# and, when bspf_sweep was built with Bullet, the Bullet peer's ns per step
# (default settings, 6 m/s, 64 agents, 600 frames, median of 3; its crowd is
# stepped body by body, without pushes, like the replay).
# When bspf_machine_probe was built, the machine's state (each core's speed,
# whether two cores share one physical core's width, a DRAM read's latency,
# a cache line's round trip between cores) is printed
# under the table, measured before and after the runs: on a shared machine a
# table's figures are comparable with another's only where these match.
# Builds nothing: a Release build is expected in ${BUILD:-build}.
#
#   scripts/perf_report.sh [--levels "arena oa_dm1 terrain ..."] [--methods "planes exact"]
#                          [--speeds "6 40"] [--runs N] [--no-bullet] [--json FILE]
#
# --json FILE also writes {"rows": [one object per table row], "machine":
# {"before": ..., "after": ...}} (machine empty without the probe).
#
# About 5 to 10 minutes for everything on 2 cores; restrict with the options.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD:-build}
shared=../shared/levels
levels="arena fan oa_dm1 oacmpdm5 oa_dm4 oa_dm5 oacmpctf3 terrain curved_room cad_building"
methods="planes exact"
speeds="6 40"
runs=3
bullet=1
json_out=
while [ $# -gt 0 ]; do
  case $1 in
    --levels) levels=$2; shift 2 ;;
    --methods) methods=$2; shift 2 ;;
    --speeds) speeds=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    --no-bullet) bullet=0; shift ;;
    --json) json_out=$2; shift 2 ;;
    -h | --help) sed -n '2,31p' "$0"; exit 0 ;;
    *) echo "perf_report: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done
for tool in compiler/bspc samples/walkers bench/bspf_replay_bench; do
  [ -x "$build/$tool" ] || { echo "perf_report: $build/$tool is missing: build Release first" >&2; exit 1; }
done

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
generated=()
for name in $levels; do
  case $name in terrain | curved_room | cad_building) generated+=(--level "$name") ;; esac
done
if [ ${#generated[@]} -gt 0 ]; then
  python3 scripts/make_detailed_levels.py --out "$tmp/generated" "${generated[@]}" >&2
fi

# Where a level's OBJ (and spawns, brushes) lives: BASE.obj, BASE.spawns.txt.
base_of() {
  case $1 in
    arena | box_room | slopes) echo "samples/$1" ;;
    terrain | curved_room | cad_building) echo "$tmp/generated/$1" ;;
    *) echo "$shared/$1" ;;
  esac
}

have_bullet=0
if [ "$bullet" = 1 ] && [ -x "$build/bench/bspf_sweep" ] &&
  "$build/bench/bspf_sweep" --default-only --method bullet --level arena \
    --agents 1 --frames 1 --repeats 1 --out "$tmp/probe.csv" >/dev/null 2>&1; then
  have_bullet=1
fi

probe() {
  [ -x "$build/bench/bspf_machine_probe" ] && "$build/bench/bspf_machine_probe" >"$tmp/machine.$1.json" ||
    true
}
probe before

selected=()
for name in $levels; do
  base=$(base_of "$name")
  if [ ! -f "$base.obj" ]; then
    echo "perf_report: $base.obj is absent: $name skipped" >&2
    continue
  fi
  selected+=("$name")
  echo "perf_report: $name" >&2
  "$build/compiler/bspc" -q "$base.obj" -o "$tmp/$name.bspf"
  brushes=()
  [ -f "$base.brushes.txt" ] && brushes=(--brushes "$base.brushes.txt")
  for method in $methods; do
    for speed in $speeds; do
      for run in $(seq "$runs"); do
        "$build/samples/walkers" "$tmp/$name.bspf" --spawns "$base.spawns.txt" "${brushes[@]}" \
          --speed "$speed" --method "$method" --json >"$tmp/$name.$method.$speed.walkers.$run.json"
      done
      "$build/bench/bspf_replay_bench" "$tmp/$name.bspf" --spawns "$base.spawns.txt" \
        --speed "$speed" --method "$method" --json >"$tmp/$name.$method.$speed.replay.json"
    done
  done
  if [ "$have_bullet" = 1 ]; then
    obj=()
    case $name in terrain | curved_room | cad_building) obj=(--obj "$base.obj") ;; esac
    "$build/bench/bspf_sweep" --default-only --method bullet --level "$name" "${obj[@]}" \
      --agents 64 --frames 600 --repeats 3 --out "$tmp/$name.bullet.csv" >/dev/null 2>&1 ||
      echo "perf_report: bspf_sweep failed on $name: no Bullet figure" >&2
  fi
done

probe after

python3 - "$tmp" "$runs" "$json_out" "${selected[*]}" "$methods" "$speeds" <<'PY'
import csv, json, os, statistics, sys
tmp, runs, json_out, levels, methods, speeds = sys.argv[1:]
runs = int(runs)


def bullet_ns(level):
    path = f"{tmp}/{level}.bullet.csv"
    if not os.path.exists(path):
        return None
    with open(path) as f:
        rows = csv.DictReader(line for line in f if not line.startswith("#"))
        for row in rows:
            if row["level"] == level and row["method"] == "bullet" and row["knob"] == "default":
                return float(row["ns_per_step"])
    return None


def fmt(v, digits=0):
    return "-" if v is None else f"{v:.{digits}f}"


table = []
print("| level | method | m/s | walkers ns/agent-step | refused | inside solid | replay ns/step | "
      "queries/step | candidates mean / p90 | overlapping | ratio mean / of means | leaves | "
      "refs/tri | Bullet ns/step (6 m/s) |")
print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
for level in levels.split():
    bullet = bullet_ns(level)
    for method in methods.split():
        for speed in speeds.split():
            walks = [json.load(open(f"{tmp}/{level}.{method}.{speed}.walkers.{r}.json"))
                     for r in range(1, runs + 1)]
            replay = json.load(open(f"{tmp}/{level}.{method}.{speed}.replay.json"))
            m = replay["methods"][0]
            w = walks[0]
            row = {
                "level": level, "method": method, "speed": float(speed),
                "walkers_ns_per_step": statistics.median(x["ns_per_step"] for x in walks),
                "refused_moves": w["refused_moves"], "inside_solid": w["inside_solid"],
                "fell_out": w["fell_out"], "triangles": replay["triangles"],
                "leaves": replay["leaves"],
                "references_per_triangle": replay["references_per_triangle"],
                "bullet_ns_per_step": bullet,
            }
            row.update({"replay_" + k: v for k, v in m.items() if k != "method"})
            table.append(row)
            print(f"| {level} | {method} | {speed} | {row['walkers_ns_per_step']:.0f} | "
                  f"{row['refused_moves']} | {'-' if w['inside_solid'] is None else w['inside_solid']} | "
                  f"{m['ns_per_step']:.0f} | {m['queries_per_step']:.2f} | "
                  f"{m['candidates_mean']:.1f} / {m['candidates_p90']:.0f} | "
                  f"{m['overlapping_mean']:.1f} | {m['ratio_mean']:.2f} / {m['ratio_of_means']:.2f} | "
                  f"{replay['leaves']} | {replay['references_per_triangle']:.2f} | {fmt(bullet)} |")
machine = {}
for when in ("before", "after"):
    path = f"{tmp}/machine.{when}.json"
    if os.path.exists(path) and os.path.getsize(path) > 0:
        machine[when] = json.load(open(path))
        print(f"\nMachine {when} the runs (bspf_machine_probe, ns): " +
              ", ".join(f"{k} {v}" for k, v in machine[when].items() if k != "case"))
if json_out:
    with open(json_out, "w") as f:
        json.dump({"rows": table, "machine": machine}, f, indent=1)
PY
