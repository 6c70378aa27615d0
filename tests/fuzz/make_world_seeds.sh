#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Remakes the seed blobs of fuzz_world (tests/fuzz/corpus/fuzz_world) with a
# bspc build: valid blobs of the smallest meshes (the OBJ seeds and a sample
# level), and broken copies of one: truncated, a flipped byte, a wrong
# version, empty. bspc output is deterministic, so the files change only
# when the format or the compiler does.
#
#   tests/fuzz/make_world_seeds.sh BSPC
set -euo pipefail
bspc=$(realpath "$1")
cd "$(dirname "$0")"
out=corpus/fuzz_world
rm -f "$out"/*
compile() { "$bspc" -q "$@"; }
compile corpus/fuzz_obj/triangle.obj -o "$out/triangle.bspf"
compile corpus/fuzz_obj/quad_relative.obj -o "$out/quad.bspf"
compile corpus/fuzz_obj/box_groups.obj -o "$out/box.bspf"
compile corpus/fuzz_obj/box_groups.obj --max-leaf-triangles 1 --query-reach 0 -o "$out/box_deep.bspf"
compile ../../samples/slopes.obj -o "$out/slopes.bspf"
size=$(stat -c %s "$out/box.bspf")
head -c $((size / 2)) "$out/box.bspf" >"$out/box_truncated.bspf"
head -c 12 "$out/box.bspf" >"$out/header_only.bspf"
: >"$out/empty.bspf"
# A byte in the middle of the blob flipped; the format version (the first
# field after the root table's offset and the identifier) made 99.
cp "$out/box.bspf" "$out/box_flipped.bspf"
printf '\xff' | dd of="$out/box_flipped.bspf" bs=1 seek=$((size / 3)) conv=notrunc status=none
python3 - "$out/box.bspf" "$out/box_wrong_version.bspf" <<'PY'
import struct, sys
data = bytearray(open(sys.argv[1], 'rb').read())
# size prefix (4), root offset (4) at 4; the root table at 4 + offset.
table = 4 + struct.unpack_from('<I', data, 4)[0]
vtable = table - struct.unpack_from('<i', data, table)[0]
field = struct.unpack_from('<H', data, vtable + 4)[0]  # format_version, field 0
struct.pack_into('<I', data, table + field, 99)
open(sys.argv[2], 'wb').write(data)
PY
ls -l "$out"
