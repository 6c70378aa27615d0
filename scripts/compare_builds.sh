#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Compares the movement step of two or more revisions on the same levels, the
# way docs/measurements.md asks for on a shared, noisy machine: each revision
# built Release (no -march) in its own worktree, each level compiled by that
# revision's own bspc (blob formats differ between revisions), then walkers
# (64 agents from the spawns, 600 frames) run interleaved, revision after
# revision, run after run, and the median of the runs' ns per agent-step
# printed with each revision's ratio to the first. Refused moves and
# iterations come from the first run (they are deterministic).
#
#   scripts/compare_builds.sh [--levels "fan oa_dm4 ..."] [--methods "planes exact"]
#                             [--speeds "6 40"] [--runs N] [--callgrind] REV REV...
#
# REV is anything git names (a commit, a branch, HEAD, main~3); "WORKTREE"
# means the current working tree, uncommitted edits included (built in
# build-compare/ here). Levels are looked up in ../shared/levels (default:
# every level there that has a spawns file). --callgrind counts instead the
# instructions per agent-step of stepBodies under valgrind (one run, about
# 30 times slower, but exact and immune to the machine's noise: the way to
# compare small changes). Builds are kept in ${BSPF_COMPARE_DIR:-/tmp/bspf-compare-$UID}
# and reused; a first build takes a few minutes per revision.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
shared="$root/../shared/levels"
levels=""
methods="planes exact"
speeds="6 40"
runs=3
callgrind=0
revs=()
while [ $# -gt 0 ]; do
  case $1 in
    --levels) levels=$2; shift 2 ;;
    --methods) methods=$2; shift 2 ;;
    --speeds) speeds=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    --callgrind) callgrind=1; shift ;;
    -h | --help) sed -n '3,22p' "$0"; exit 0 ;;
    -*) echo "compare_builds: unknown option $1 (see --help)" >&2; exit 2 ;;
    *) revs+=("$1"); shift ;;
  esac
done
[ ${#revs[@]} -ge 2 ] || { echo "compare_builds: name at least two revisions (see --help)" >&2; exit 2; }
[ -d "$shared" ] || { echo "compare_builds: $shared not found: the shared levels are needed" >&2; exit 1; }
if [ -z "$levels" ]; then
  for spawns in "$shared"/*.spawns.txt; do levels+="$(basename "$spawns" .spawns.txt) "; done
fi
if [ $callgrind = 1 ] && ! command -v valgrind >/dev/null; then
  echo "compare_builds: --callgrind needs valgrind (apt-get install valgrind)" >&2
  exit 1
fi
work="${BSPF_COMPARE_DIR:-/tmp/bspf-compare-$(id -u)}"
mkdir -p "$work"

# Builds revision $1 (Release, walkers and bspc) and compiles the levels with
# it; prints the directory holding build/ and levels/.
prepare() {
  local rev=$1 dir src
  if [ "$rev" = WORKTREE ]; then
    dir="$work/worktree"
    src="$root"
  else
    local sha
    sha=$(git -C "$root" rev-parse --verify --quiet "$rev^{commit}") ||
      { echo "compare_builds: $rev is not a revision" >&2; exit 2; }
    dir="$work/$sha"
    src="$dir/src"
    if [ ! -d "$src" ]; then
      git -C "$root" worktree add --detach "$src" "$sha" >/dev/null 2>&1
    fi
  fi
  mkdir -p "$dir/levels"
  local build="$dir/build"
  [ "$rev" = WORKTREE ] && build="$root/build-compare"
  if [ ! -f "$build/build.ninja" ] && [ ! -f "$build/Makefile" ]; then
    local generator=()
    command -v ninja >/dev/null && generator=(-G Ninja)
    cmake -S "$src" -B "$build" -DCMAKE_BUILD_TYPE=Release "${generator[@]}" >/dev/null
  fi
  cmake --build "$build" --target walkers bspc -j"$(nproc)" >/dev/null
  for level in $levels; do
    local blob="$dir/levels/$level.bspf"
    if [ ! -f "$blob" ] || [ "$build/compiler/bspc" -nt "$blob" ]; then
      "$build/compiler/bspc" "$shared/$level.obj" -o "$blob" >/dev/null
    fi
  done
  ln -sfn "$build" "$dir/bin"
  echo "$dir"
}

dirs=()
for rev in "${revs[@]}"; do
  echo "compare_builds: preparing $rev" >&2
  dirs+=("$(prepare "$rev")")
done

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
walk() {  # dir level method speed -> JSON on stdout
  "$1/bin/samples/walkers" "$1/levels/$2.bspf" --spawns "$shared/$2.spawns.txt" \
    --speed "$4" --method "$3" --json
}

header="| level | method | m/s |"
rule="|---|---|---:|"
unit="ns"
[ $callgrind = 1 ] && unit="instr"
for k in "${!revs[@]}"; do
  header+=" ${revs[$k]} $unit |"
  rule+="---:|"
  [ "$k" -gt 0 ] && header+=" ${revs[0]} / ${revs[$k]} |" && rule+="---:|"
done
for rev in "${revs[@]}"; do header+=" refused $rev |"; rule+="---:|"; done
echo "$header"
echo "$rule"
for level in $levels; do
  for method in $methods; do
    for speed in $speeds; do
      if [ $callgrind = 1 ]; then
        for k in "${!dirs[@]}"; do
          valgrind --tool=callgrind --callgrind-out-file="$tmp/cg.$k" \
            "${dirs[$k]}/bin/samples/walkers" "${dirs[$k]}/levels/$level.bspf" \
            --spawns "$shared/$level.spawns.txt" --speed "$speed" --method "$method" --json \
            >"$tmp/$k.1.json" 2>/dev/null
          callgrind_annotate --inclusive=yes "$tmp/cg.$k" 2>/dev/null |
            awk '/bspf::stepBodies\(/ && !found { gsub(",", "", $1); print $1; found = 1 }' >"$tmp/$k.ir"
        done
      else
        for run in $(seq "$runs"); do
          for k in "${!dirs[@]}"; do walk "${dirs[$k]}" "$level" "$method" "$speed" >"$tmp/$k.$run.json"; done
        done
      fi
      python3 - "$tmp" "${#dirs[@]}" "$runs" "$callgrind" "$level" "$method" "$speed" <<'PY'
import json, statistics, sys
tmp, count, runs, callgrind, level, method, speed = sys.argv[1:]
count, runs, callgrind = int(count), int(runs), callgrind == "1"
values, refused = [], []
for k in range(count):
    first = json.load(open(f"{tmp}/{k}.1.json"))
    refused.append(first["refused_moves"])
    if callgrind:
        values.append(int(open(f"{tmp}/{k}.ir").read() or 0) / first["steps"])
    else:
        values.append(statistics.median(
            json.load(open(f"{tmp}/{k}.{r}.json"))["ns_per_step"] for r in range(1, runs + 1)))
cells = []
for k, v in enumerate(values):
    cells.append(f"{v:.0f}")
    if k > 0:
        cells.append(f"{values[0] / v:.2f}" if v else "-")
cells += [str(r) for r in refused]
print(f"| {level} | {method} | {speed} | " + " | ".join(cells) + " |", flush=True)
PY
    done
  done
done
