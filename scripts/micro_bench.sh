#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Microbenchmarks of the collision primitives (bench/micro_bench.cpp): installs
# Google Benchmark if needed, builds bspf_micro_bench (Release, in
# build-bench), runs every benchmark 5 times and prints the medians, ns per
# call. Extra arguments go to the benchmark (e.g. --benchmark_filter=PreCheck).
set -euo pipefail
cd "$(dirname "$0")/.."
BSPF_WITH_BENCH=1 scripts/install-deps.sh
cmake -S . -B build-bench -DCMAKE_BUILD_TYPE=Release -DBSPF_BUILD_TESTS=OFF >/dev/null
cmake --build build-bench --target bspf_micro_bench -j"$(nproc)"
build-bench/bench/bspf_micro_bench --benchmark_repetitions=5 \
  --benchmark_report_aggregates_only=true --benchmark_color=false "$@" |
  awk '/^Benchmark/ || /^-+$/ || /_median/'
