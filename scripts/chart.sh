#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Charts speed against accuracy for the runtime's two narrow phases (planes,
# exact) and a Bullet peer: installs the benchmark packages when missing,
# builds bspf_sweep (Release, build-bench), runs it over the sample levels and
# ../shared/levels (when present) and renders the chart with gnuplot.
#
#   scripts/chart.sh [bspf_sweep options...]   e.g. --quick for a smoke run
#
# Writes docs/speed-accuracy.csv, docs/speed-accuracy.svg and
# docs/speed-accuracy.png. About 10 minutes on 2 cores (the build included).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD:-build-bench}
jobs=${JOBS:-$(nproc 2>/dev/null || echo 2)}

BSPF_WITH_BENCH=1 scripts/install-deps.sh
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DBSPF_BUILD_TESTS=OFF >/dev/null
cmake --build "$build" --target bspf_sweep -j "$jobs"

mkdir -p docs
"$build/bench/bspf_sweep" --out docs/speed-accuracy.csv "$@"
gnuplot -e "csv='docs/speed-accuracy.csv'; out='docs/speed-accuracy'" bench/speed_accuracy.gp
echo "chart: wrote docs/speed-accuracy.csv, docs/speed-accuracy.svg, docs/speed-accuracy.png"
