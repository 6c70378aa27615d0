#!/usr/bin/env bash
# The main job on a bundled sample: install what is needed, build (Release),
# compile samples/arena.obj into a .bspf blob and describe it.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DBSPF_BUILD_TESTS=OFF >/dev/null
cmake --build build -j"$(nproc)"
mkdir -p out
build/compiler/bspc samples/arena.obj -o out/arena.bspf --stats-json out/arena.stats.json
build/compiler/bspc --info out/arena.bspf
