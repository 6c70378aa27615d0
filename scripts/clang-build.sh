#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Builds every target with clang (Debian 12: clang 14) in build-clang, with
# the project's warnings (-Wall -Wextra -Wpedantic, CMakeLists.txt) as
# errors, then runs the test suite built by it through ctest.
#
#   scripts/clang-build.sh            # build and test
#   BSPF_CLANG_TESTS=0 scripts/clang-build.sh   # build only
#
# BUILD: the build folder (default build-clang).
set -euo pipefail
cd "$(dirname "$0")/.."
BSPF_WITH_CLANG=1 scripts/install-deps.sh
build="${BUILD:-build-clang}"
jobs="$(nproc)"

cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_CXX_FLAGS="-Werror" -DCMAKE_CXX_FLAGS_RELEASE="-O2" >/dev/null
cmake --build "$build" -j"$jobs"
echo "clang-build: every target built by $(clang++ --version | head -n 1), no warning"
if [ "${BSPF_CLANG_TESTS:-1}" = 1 ]; then
  (cd "$build" && ctest -j"$jobs" --output-on-failure)
fi
