#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Mutation check: do the tests notice a broken step, query or loader?
#
# Applies each mutation of scripts/mutations.txt (one small deliberate
# breakage of the runtime) to a scratch copy of the tracked tree, rebuilds
# what the tests run, runs the tests until the first failure, and prints one
# line per mutation: `killed` (a test failed), `SURVIVED` (every test passed:
# a behaviour nothing pins), `invalid: ...` (the text is not in the file, or
# the mutant does not build). Closes with `N killed, M survived, K invalid`
# and exits non-zero unless every mutation was killed.
#
# Run it whenever the movement step, the query or the loader changes, and
# keep the list current: when a mutation's text no longer exists, write the
# equivalent breakage of the new code. Not part of CI: each mutation costs an
# incremental rebuild (seconds for a .cpp, minutes for a header every test
# includes) and a test run.
#
#   scripts/mutation_check.sh [LIST] [FILTER]
#
# LIST defaults to scripts/mutations.txt; FILTER (a regular expression)
# keeps only the entries whose file or text matches it. The scratch copy and
# its build live in $BSPF_MUTATION_DIR (default /tmp/bspf-mutation-<uid>) and
# are reused across runs, so only what changed is rebuilt.
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
list="${1:-$root/scripts/mutations.txt}"
filter="${2:-}"
scratch="${BSPF_MUTATION_DIR:-/tmp/bspf-mutation-$(id -u)}"
jobs="${BSPF_MUTATION_JOBS:-2}"
tree="$scratch/tree" build="$scratch/build"
mkdir -p "$tree"

# The tracked files (and uncommitted edits to them), copied only when they
# differ, so the unchanged ones keep their timestamps and the incremental
# build stays valid. A changed file gets a new timestamp: kept, the source's
# could be older than an object the last run built from its older content
# (edited while that run was building), and the edit would never be built.
(cd "$root" && git ls-files -z --cached --others --exclude-standard) |
  while IFS= read -r -d '' file; do
    [ -f "$root/$file" ] || continue
    if ! cmp -s "$root/$file" "$tree/$file"; then
      mkdir -p "$(dirname "$tree/$file")"
      cp "$root/$file" "$tree/$file"
    fi
  done

cmake -S "$tree" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS_RELEASE="-O2" \
  >"$scratch/configure.log" 2>&1 || { echo "configure failed: $scratch/configure.log"; exit 2; }
# The test binary and what its tests run (bspc, walkers through
# add_dependencies), and the sweep that the one non-Catch test runs.
build_targets() { cmake --build "$build" -j"$jobs" --target bspf_tests bspf_sweep >"$scratch/build.log" 2>&1; }
build_targets || { echo "the unmutated tree does not build: $scratch/build.log"; exit 2; }

# Runtime tests first (they kill most mutants, fast), then the rest; the
# first failure ends the run. Then the non-Catch tests through ctest.
run_tests() {
  local tests="$build/tests/bspf_tests"
  "$tests" "[runtime]" --abort >"$scratch/test.log" 2>&1 &&
    "$tests" "~[runtime]" --abort >>"$scratch/test.log" 2>&1 &&
    (cd "$build" && ctest -R '^bspf_sweep' --stop-on-failure) \
      >>"$scratch/test.log" 2>&1
}

# apply FILE FIND REPLACE (escaped: \n newline, \t tab, \\ backslash):
# rewrites FILE in the scratch tree, exit 3 when FIND is not in it.
apply() {
  python3 - "$@" <<'PY'
import sys
def unescape(s):
    out, i = [], 0
    while i < len(s):
        if s[i] == "\\" and i + 1 < len(s):
            out.append({"n": "\n", "t": "\t", "\\": "\\"}.get(s[i + 1], "\\" + s[i + 1]))
            i += 2
        else:
            out.append(s[i])
            i += 1
    return "".join(out)
path, find, replace = sys.argv[1], unescape(sys.argv[2]), unescape(sys.argv[3])
text = open(path).read()
if text.count(find) != 1:
    sys.exit(3 if text.count(find) == 0 else 4)
open(path, "w").write(text.replace(find, replace))
PY
}

killed=0 survived=0 invalid=0
number=0
while IFS=$'\t' read -r file find replace note || [ -n "$file" ]; do
  case "$file" in '' | '#'*) continue ;; esac
  number=$((number + 1))
  label="$(printf '%2d %s: %s -> %s' "$number" "$file" "$find" "$replace")"
  [ ${#label} -gt 150 ] && label="${label:0:147}..."
  if [ -n "$filter" ] && ! grep -Eq -- "$filter" <<<"$file$find"; then continue; fi
  target="$tree/$file"
  cp -p "$target" "$scratch/original"
  apply "$target" "$find" "$replace"
  status=$?
  if [ $status -eq 3 ]; then
    echo "invalid: text not found  $label"
    invalid=$((invalid + 1))
  elif [ $status -ne 0 ]; then
    echo "invalid: text not unique  $label"
    invalid=$((invalid + 1))
  elif ! build_targets; then
    echo "invalid: does not build  $label"
    invalid=$((invalid + 1))
  elif run_tests; then
    echo "SURVIVED  $label${note:+  ($note)}"
    survived=$((survived + 1))
  else
    echo "killed    $label"
    killed=$((killed + 1))
  fi
  # Restored byte for byte, but with a new timestamp: the next build
  # recompiles the file back.
  cp "$scratch/original" "$target"
done <"$list"

echo "$killed killed, $survived survived, $invalid invalid"
[ $survived -eq 0 ] && [ $invalid -eq 0 ]
