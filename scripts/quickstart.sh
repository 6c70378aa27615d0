#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The main job on a bundled level: install what is needed, build (Release),
# compile samples/arena.obj into out/arena.bspf, describe the blob, then run
# the walkers sample on it (64 agents, 600 frames, from the level's spawns)
# checking every agent against the level's brushes. Prints walkers' JSON.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DBSPF_BUILD_TESTS=OFF >/dev/null
cmake --build build -j"$(nproc)"
mkdir -p out
build/compiler/bspc -q samples/arena.obj -o out/arena.bspf
build/compiler/bspc --info out/arena.bspf
build/samples/walkers out/arena.bspf --spawns samples/arena.spawns.txt \
  --brushes samples/arena.brushes.txt --json
