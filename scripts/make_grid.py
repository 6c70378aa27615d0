#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Write a large heightfield grid as an OBJ, for bspc's peak memory and speed.

    python3 scripts/make_grid.py OUT.obj [--cells 1000]

--cells N: N x N squares of 0.5 m, two triangles each (1000: 2 million
triangles, a 72 MB OBJ). Heights are a gentle sine wave plus up to 1 cm of
noise from a fixed seed, so no two neighbouring triangles are coplanar and
every run writes the same file.
"""
import argparse
import math
import random


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out")
    parser.add_argument("--cells", type=int, default=1000)
    args = parser.parse_args()
    n = args.cells
    rng = random.Random(5)
    with open(args.out, "w") as f:
        for j in range(n + 1):
            for i in range(n + 1):
                y = 0.3 * math.sin(i * 0.07) * math.cos(j * 0.05) + rng.uniform(-0.01, 0.01)
                f.write(f"v {i * 0.5:.4f} {y:.4f} {j * 0.5:.4f}\n")
        for j in range(n):
            for i in range(n):
                a = j * (n + 1) + i + 1
                b, c = a + 1, a + n + 1
                f.write(f"f {a} {c} {b}\nf {b} {c} {c + 1}\n")


if __name__ == "__main__":
    main()
