#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes the seed inputs of fuzz_mesh (tests/fuzz/corpus/fuzz_mesh) in the
format fuzz_mesh.cpp decodes: a settings byte, a vertex count, the vertices,
then triangles of three 16-bit indices."""
import os
import struct

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus", "fuzz_mesh")


def seed(name, flags, vertices, triangles):
    raw = flags & 128
    data = bytearray([flags, len(vertices)])
    for v in vertices:
        data += struct.pack("<3f", *v) if raw else struct.pack("<3h", *(round(c * 64) for c in v))
    for t in triangles:
        data += struct.pack("<3H", *t)
    with open(os.path.join(OUT, name), "wb") as f:
        f.write(data)


# A unit box, counter-clockwise seen from outside.
BOX_V = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
BOX_T = [(0, 4, 6), (0, 6, 2), (1, 3, 7), (1, 7, 5), (0, 1, 5), (0, 5, 4),
         (2, 6, 7), (2, 7, 3), (0, 2, 3), (0, 3, 1), (4, 5, 7), (4, 7, 6)]
# A floor with a 30-degree ramp on it.
RAMP_V = [(-4, 0, -4), (-4, 0, 4), (4, 0, 4), (4, 0, -4), (0, 0, -1), (0, 0, 1), (2, 1.15, 1),
          (2, 1.15, -1)]
RAMP_T = [(0, 1, 2), (0, 2, 3), (4, 5, 6), (4, 6, 7)]

os.makedirs(OUT, exist_ok=True)
seed("box", 0x07, BOX_V, BOX_T)
seed("box_deep", 0x08, BOX_V, BOX_T)
seed("ramp", 0x03, RAMP_V, RAMP_T)
seed("ramp_raw", 0x80 | 0x02, RAMP_V, RAMP_T)
# Welding, repeats and collapses: a repeated corner, a duplicate, the back face.
seed("degenerate", 0x20, BOX_V + [(0, 0, 0.01)], [(0, 0, 1), (0, 4, 6), (0, 4, 6), (6, 4, 0), (0, 8, 4)])
# Beyond the coordinate bound, and not finite.
seed("huge_raw", 0x80, [(0, 0, 0), (1e19, 0, 0), (0, 0, -1e19)], [(0, 1, 2)])
seed("nan_raw", 0x80, [(0, 0, 0), (float("nan"), 0, 0), (0, 0, -1)], [(0, 1, 2)])
