#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Builds the libFuzzer targets (tests/fuzz) with clang, AddressSanitizer and
# UndefinedBehaviorSanitizer, and runs each for a bounded time from its
# committed seed corpus (tests/fuzz/corpus/<target>). Fails on any finding
# (a crash, a sanitizer report, a broken promise, a leak, an input slower
# than the timeout); the input that caused it is saved under
# build-fuzz/findings/. docs/fuzzing.md says how to reproduce one.
#
#   scripts/fuzz.sh [SECONDS]    seconds per target: the argument, else
#                                $BSPF_FUZZ_SECONDS, else 60; 0 skips
#                                fuzzing (nothing is built)
#
# Inputs found on the way go to build-fuzz/corpus/<target>, never into the
# committed seeds. Without clang++ it says so and does nothing.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-${BSPF_FUZZ_SECONDS:-60}}"
case $seconds in '' | *[!0-9]*) echo "fuzz.sh: seconds must be a whole number, not '$seconds'" >&2; exit 2 ;; esac
targets=(fuzz_world fuzz_obj fuzz_mesh)
if [ "$seconds" -eq 0 ]; then
  echo "fuzz.sh: 0 seconds: fuzzing skipped"
  exit 0
fi

if ! command -v clang++ >/dev/null; then
  echo "fuzz.sh: clang++ not found (scripts/install-deps.sh installs it): fuzzing skipped"
  exit 0
fi

# Optimised, with assert() live: an assert is a promise too.
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O2 -g" \
  -DCMAKE_CXX_COMPILER=clang++ -DBSPF_BUILD_FUZZERS=ON -DBSPF_BUILD_TESTS=OFF >/dev/null
cmake --build build-fuzz -j"$(nproc)" --target "${targets[@]}"

mkdir -p build-fuzz/findings
# Leaks inside assimp (a system library) are not ours to fix: lsan.supp.
export LSAN_OPTIONS="suppressions=$PWD/tests/fuzz/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
for target in "${targets[@]}"; do
  mkdir -p "build-fuzz/corpus/$target"
  echo "fuzz.sh: $target for ${seconds} s"
  # The first folder takes the new inputs; the seeds are only read.
  # -timeout: one input slower than this is a finding (a hang);
  # -rss_limit_mb: so is using more memory than this.
  status=0
  "build-fuzz/tests/fuzz/$target" -max_total_time="$seconds" -timeout=25 -rss_limit_mb=2560 \
    -print_final_stats=1 -artifact_prefix="build-fuzz/findings/$target-" \
    "build-fuzz/corpus/$target" "tests/fuzz/corpus/$target" >"build-fuzz/$target.log" 2>&1 ||
    status=$?
  # The figures: the seeds' coverage, the run's, executions and speed.
  grep -E '^#[0-9]+[[:space:]]+(INITED|DONE)|^stat::(number_of_executed_units|average_exec_per_sec|peak_rss_mb)' \
    "build-fuzz/$target.log" || true
  if [ "$status" -ne 0 ]; then
    tail -n 60 "build-fuzz/$target.log"
    echo "fuzz.sh: $target found a failure (exit $status): the input is in build-fuzz/findings/," \
      "the whole log in build-fuzz/$target.log" >&2
    exit 1
  fi
done
echo "fuzz.sh: no findings"
