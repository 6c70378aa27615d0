#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The tree build's portable paths (what a CPU without SSE2 runs) give the
# same blobs as its SSE2 paths: bspc built with -DBSPC_PORTABLE_ONLY=ON
# compiles the sample levels (and the shared levels, when present) byte for
# byte as the given bspc does.
#
#   scripts/check_portable_tree.sh BSPC     BSPC: a bspc built the usual way
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -eq 1 ] && [ -x "$1" ] || { echo "usage: scripts/check_portable_tree.sh BSPC" >&2; exit 2; }
usual=$1
build=${BUILD:-build-portable}
jobs=${JOBS:-$(nproc 2>/dev/null || echo 2)}
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DBSPC_PORTABLE_ONLY=ON \
  -DBSPF_BUILD_TESTS=OFF -DBSPF_BUILD_BENCH=OFF -DBSPF_BUILD_SAMPLES=OFF >/dev/null
cmake --build "$build" --target bspc -j "$jobs"

scripts/same_blobs.sh "the portable tree build" "$usual" "$build/compiler/bspc"
