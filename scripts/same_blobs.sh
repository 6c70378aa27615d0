#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Two bspc executables write the same blobs: each compiles the sample levels
# (and the shared levels, when present) at 1 and 2 threads, and every blob
# must match the first executable's at 1 thread byte for byte. For builds
# that must not change the bytes: another compiler (scripts/test.sh checks
# clang's bspc against GCC's), the tree build's portable paths
# (scripts/check_portable_tree.sh).
#
#   scripts/same_blobs.sh WHAT BSPC_A BSPC_B    WHAT names B in the messages
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -eq 3 ] && [ -x "$2" ] && [ -x "$3" ] ||
  { echo "usage: scripts/same_blobs.sh WHAT BSPC_A BSPC_B" >&2; exit 2; }
what=$1 first=$2 second=$3
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
shared=${BSPF_SHARED_LEVELS:-../shared/levels}
levels=(samples/*.obj)
[ -d "$shared" ] && levels+=("$shared"/*.obj)
for level in "${levels[@]}"; do
  name=$(basename "$level" .obj)
  "$first" -q "$level" -o "$out/$name.a.bspf" --threads 1
  for threads in 1 2; do
    "$second" -q "$level" -o "$out/$name.b.bspf" --threads "$threads"
    if ! cmp -s "$out/$name.a.bspf" "$out/$name.b.bspf"; then
      echo "same_blobs: $level: $what wrote a different blob at $threads threads" >&2
      exit 1
    fi
  done
done
echo "same_blobs: ${#levels[@]} levels, $what wrote the same blobs"
