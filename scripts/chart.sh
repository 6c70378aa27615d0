#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Charts speed against accuracy for the runtime's two narrow phases (planes,
# exact) and a Bullet peer: installs the benchmark packages when missing,
# builds bspf_sweep (Release, build-bench), runs it over the sample levels and
# the shared levels and renders the chart with gnuplot (labels laid out by
# bench/chart_labels.py so that none overlaps).
#
#   scripts/chart.sh                    the full run: writes docs/speed-accuracy.{csv,svg,png}
#   scripts/chart.sh --plot-only        re-renders docs/speed-accuracy.{svg,png} from the
#                                       committed docs/speed-accuracy.csv (seconds, no build)
#   scripts/chart.sh --out-dir DIR [bspf_sweep options...]
#                                       writes DIR/speed-accuracy.*, e.g. --quick for a smoke run
#
# The full run needs the shared levels (${BSPF_SHARED_LEVELS:-../shared/levels}):
# without them, or with bspf_sweep options, it measures something else than
# the committed chart, so it refuses to write into docs/ (give --out-dir).
# It prints how long it took (a long run: every knob of three methods on
# nine levels).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD:-build-bench}
jobs=${JOBS:-$(nproc 2>/dev/null || echo 2)}

outDir=docs
plotOnly=0
sweepArgs=()
while [ $# -gt 0 ]; do
  case $1 in
    --plot-only) plotOnly=1 ;;
    --out-dir)
      [ $# -ge 2 ] || { echo "chart.sh: error: --out-dir needs a folder" >&2; exit 2; }
      outDir=$2
      shift ;;
    -h | --help) sed -n '2,19p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) sweepArgs+=("$1") ;;
  esac
  shift
done

render() {  # CSV OUT-PREFIX
  local layout
  layout=$(mktemp -d)
  python3 bench/chart_labels.py "$1" "$layout/layout"
  gnuplot -e "csv='$1'; layout='$layout/layout'; out='$2'" bench/speed_accuracy.gp
  rm -r "$layout"
  echo "chart: wrote $2.svg, $2.png"
}

if [ "$plotOnly" = 1 ]; then
  [ ${#sweepArgs[@]} -eq 0 ] || { echo "chart.sh: error: --plot-only takes no bspf_sweep options" >&2; exit 2; }
  [ -f "$outDir/speed-accuracy.csv" ] || { echo "chart.sh: error: $outDir/speed-accuracy.csv: no such file" >&2; exit 1; }
  render "$outDir/speed-accuracy.csv" "$outDir/speed-accuracy"
  exit 0
fi

shared=${BSPF_SHARED_LEVELS:-../shared/levels}
if [ "$outDir" = docs ]; then
  if [ ! -d "$shared" ]; then
    echo "chart.sh: error: $shared: no such folder: the committed chart pools the shared levels;" \
      "set BSPF_SHARED_LEVELS, or give --out-dir DIR to chart the sample levels only" >&2
    exit 1
  fi
  if [ ${#sweepArgs[@]} -gt 0 ]; then
    echo "chart.sh: error: bspf_sweep options (${sweepArgs[*]}) change what is measured;" \
      "give --out-dir DIR to write elsewhere than docs/" >&2
    exit 2
  fi
fi

BSPF_WITH_BENCH=1 scripts/install-deps.sh
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DBSPF_BUILD_TESTS=OFF >/dev/null
cmake --build "$build" --target bspf_sweep -j "$jobs"

mkdir -p "$outDir"
"$build/bench/bspf_sweep" --out "$outDir/speed-accuracy.csv" "${sweepArgs[@]+"${sweepArgs[@]}"}"
render "$outDir/speed-accuracy.csv" "$outDir/speed-accuracy"
echo "chart: took $((SECONDS / 60)) min $((SECONDS % 60)) s"
