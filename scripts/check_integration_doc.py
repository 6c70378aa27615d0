#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# Checks that every ```cpp block of docs/integration.md is in
# samples/game_loop.cpp line for line (indentation aside), so the worked
# example cannot drift from the program the tests build and run.
import re
import sys

root = sys.argv[1] if len(sys.argv) > 1 else "."
doc = open(f"{root}/docs/integration.md").read()
source = [line.strip() for line in open(f"{root}/samples/game_loop.cpp").read().split("\n")]
blocks = re.findall(r"```cpp\n(.*?)```", doc, re.S)
if not blocks:
    sys.exit("check_integration_doc: docs/integration.md has no cpp block")
for block in blocks:
    lines = [line.strip() for line in block.rstrip().split("\n")]
    if not any(source[i:i + len(lines)] == lines for i in range(len(source))):
        sys.exit(f"check_integration_doc: not in samples/game_loop.cpp:\n{block}")
print(f"check_integration_doc: {len(blocks)} blocks, all in samples/game_loop.cpp")
