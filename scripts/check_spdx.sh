#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Every project source file (C++, the schema, CMake, scripts, the manual page)
# carries an SPDX licence identifier in its first lines: lists those that do
# not and exits 1, or says how many were checked. Generated files (the sample
# meshes, docs' CSV, SVG and PNG) and prose are not sources. Run from
# anywhere; reads git's file list, or every file when not in a checkout.
set -euo pipefail
cd "$(dirname "$0")/.."
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  files=$(git ls-files --cached --others --exclude-standard)
else
  files=$(find . -path ./.git -prune -o -path './build*' -prune -o -type f -print | sed 's|^\./||')
fi
sources=$(grep -E '\.(cpp|h|hpp|fbs|cmake|in|sh|py|gp|1)$|(^|/)CMakeLists\.txt$|^\.ci/run$' <<<"$files" |
          while read -r f; do [ -f "$f" ] && echo "$f"; done || true)
missing=0 checked=0
while read -r f; do
  checked=$((checked + 1))
  if ! grep -q 'SPDX-License-Identifier: MIT' <<<"$(head -n 3 "$f")"; then
    echo "no SPDX-License-Identifier line: $f"
    missing=$((missing + 1))
  fi
done <<<"$sources"
[ "$missing" = 0 ] || exit 1
echo "ok: $checked source files carry SPDX-License-Identifier: MIT"
