#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The runtime and its tests on Windows: cross-compiles tests/windows (the
# runtime, the compiler's in-memory stages, every test in tests/runtime) with
# Debian's mingw-w64 toolchain (cmake/mingw-w64.cmake) into build-windows, and
# runs the test program under wine. The sample levels the tests open from
# files are compiled first by the host's bspc, since the Windows build has no
# importer.
#
#   BSPC=build-test/compiler/bspc scripts/cross-windows.sh [catch2 test spec...]
#
# BSPC: a host bspc (default build/compiler/bspc). BUILD: the build folder
# (default build-windows). BSPF_WINDOWS_TIMEOUT: seconds the wine run may
# take (default 600). Installs the toolchain and wine when missing
# (BSPF_WITH_WINDOWS=1 scripts/install-deps.sh). The wine prefix is a fresh
# temporary folder, removed at the end.
set -euo pipefail
cd "$(dirname "$0")/.."
BSPF_WITH_WINDOWS=1 scripts/install-deps.sh
bspc="${BSPC:-build/compiler/bspc}"
build="${BUILD:-build-windows}"
if [ ! -x "$bspc" ]; then
  echo "cross-windows: no host bspc at $bspc (build it, or set BSPC)" >&2
  exit 1
fi

blobs="$build/sample-blobs"
mkdir -p "$blobs"
for name in arena box_room slopes; do
  "$bspc" "samples/$name.obj" -o "$blobs/$name.bspf" >/dev/null
  # compileSampleWithSplits (tests/support/test_support.h)
  "$bspc" "samples/$name.obj" -o "$blobs/$name.reach1.bspf" --query-reach 1 >/dev/null
done

cmake -S tests/windows -B "$build" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_FLAGS_RELEASE="-O2" \
  -DCMAKE_TOOLCHAIN_FILE="$PWD/cmake/mingw-w64.cmake" \
  -DBSPF_SAMPLE_BLOBS_DIR="$PWD/$blobs" >/dev/null
cmake --build "$build" -j"$(nproc)" --target bspf_runtime_tests

prefix="$(mktemp -d -t bspf-wine-XXXXXX)"
trap 'wineserver -k >/dev/null 2>&1 || true; rm -rf "$prefix"' EXIT
export WINEPREFIX="$prefix" WINEDEBUG=-all WINEDLLOVERRIDES="mscoree,mshtml=" DISPLAY=
# No shared levels under wine: their tests need the importer.
export BSPF_SHARED_LEVELS="$prefix/no-shared-levels"
# The prefix's first-run setup, quietly (without wine32 it says it misses
# 32-bit parts, which 64-bit programs do not need).
wineboot --init >/dev/null 2>&1 || true
echo "cross-windows: running the runtime tests under $(wine --version)"
timeout "${BSPF_WINDOWS_TIMEOUT:-600}" wine "$build/bspf_runtime_tests.exe" "$@"
