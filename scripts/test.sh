#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The whole test suite: install what is needed; build with AddressSanitizer
# and UndefinedBehaviorSanitizer and run the tests that feed hostile input;
# build with ThreadSanitizer and run the threading tests; fuzz each libFuzzer
# target for a minute (scripts/fuzz.sh); build optimised with assertions on;
# build everything with clang and run its tests (scripts/clang-build.sh),
# and check its bspc writes the same blobs as GCC's (scripts/same_blobs.sh);
# cross-compile the runtime and its tests for Windows and run them under wine
# (scripts/cross-windows.sh); check that the tree build's portable paths
# write the same blobs as its SSE2 ones (scripts/check_portable_tree.sh);
# then run every test of the optimised build through ctest (its summary
# closes the output).
set -euo pipefail
cd "$(dirname "$0")/.."
# With the benchmark packages, so the Bullet peer and the microbenchmarks are
# built, and the sweep's smoke test runs, too.
# The clang, mingw-w64 and wine packages for the ports below, in the same
# install.
BSPF_WITH_BENCH=1 BSPF_WITH_WINDOWS=1 BSPF_WITH_CLANG=1 scripts/install-deps.sh
jobs="$(nproc)"

if [ "${BSPF_SKIP_SANITIZERS:-0}" != 1 ]; then
  cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Debug \
    -DCMAKE_CXX_FLAGS="-O1 -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer" \
    >/dev/null
  cmake --build build-asan -j"$jobs" --target bspf_tests
  echo "sanitizer run: loader, query, clean, bad-input, movement and stability tests"
  build-asan/tests/bspf_tests "[loader],[query]~[shared-levels],[clean],[bad-input],[movement],[stability]"

  # The thread pool and the parallel step: a data race between the threads
  # that step a crowd is reported here even when the results happen to match.
  cmake -S . -B build-tsan -DCMAKE_BUILD_TYPE=Debug \
    -DCMAKE_CXX_FLAGS="-O1 -fsanitize=thread -fno-omit-frame-pointer" >/dev/null
  cmake --build build-tsan -j"$jobs" --target bspf_tests
  echo "thread sanitizer run: the threading tests"
  TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" build-tsan/tests/bspf_tests "[threads]"
fi

# Fuzzing (docs/fuzzing.md): each libFuzzer target for $BSPF_FUZZ_SECONDS
# seconds (default 60; 0 skips it) from its seed corpus, under AddressSanitizer
# and UndefinedBehaviorSanitizer. A finding fails the run.
scripts/fuzz.sh

# Optimised, but with assert() live: tests check contracts too.
cmake -S . -B build-test -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS_RELEASE="-O2 -g" >/dev/null
cmake --build build-test -j"$jobs"

if [ "${BSPF_SKIP_PORTS:-0}" != 1 ]; then
  # Every target built with clang, warnings as errors, and its tests run.
  timeout 1500 scripts/clang-build.sh
  # Blobs do not depend on the compiler that built bspc.
  scripts/same_blobs.sh "clang's bspc" build-test/compiler/bspc build-clang/compiler/bspc
  # The runtime and its tests cross-compiled for Windows and run under wine;
  # this build's bspc compiles the sample levels they open.
  BSPC=build-test/compiler/bspc timeout 900 scripts/cross-windows.sh
fi

# The tree build's portable paths, built on this CPU too, against its SSE2
# paths: the same blobs.
scripts/check_portable_tree.sh build-test/compiler/bspc

(cd build-test && ctest -j"$jobs" --output-on-failure)
