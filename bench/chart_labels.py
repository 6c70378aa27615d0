#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Lays out the labels of the speed/accuracy chart so that none overlaps.

Reads bspf_sweep's CSV (the rows of level "all"), computes where each point
falls on the page of bench/speed_accuracy.gp (its fixed margins, log axes and
the ranges this script chooses), then moves each label, starting just right
of its point, apart from every other label and every point by vertical
pushes, repeated until no two overlap; a label moved away from its point is
joined to it by a thin line. Writes, for gnuplot:

  OUT.dat     panel,method,point_x,point_y,label_x,label_y,text,is_default
  OUT.gp      the axis ranges (xmin, xmax, ymin1, ymax1, ymin2, ymax2) and the
              number of levels pooled (levels)

    python3 bench/chart_labels.py docs/speed-accuracy.csv /tmp/layout

Panel 1 plots the largest penetration (labelled when at or above the floor);
panel 2 the p99 deviation (always labelled).
"""
import csv
import math
import re
import sys

# Page and plot areas, as fractions of the page: must match speed_accuracy.gp.
WIDTH, HEIGHT = 1400, 720
PANELS = {1: (0.075, 0.475), 2: (0.575, 0.975)}  # left, right edge
BOTTOM, TOP = 0.10, 0.88
CHAR_W, LINE_H = 5.6, 11.0  # pixels, for the labels' font (sans 8 in the PNG)
FLOOR = 1e-4
METHODS = ["planes", "exact", "bullet"]


def short(knob, value):
    if knob == "default":
        return "default"
    return ("it " + value) if knob == "iterations" else knob + " " + value


def main():
    csv_path, out = sys.argv[1], sys.argv[2]
    levels = "?"
    rows = []
    with open(csv_path) as f:
        lines = []
        for line in f:
            if line.startswith("#"):
                m = re.match(r"# bspf_sweep: (\d+) levels", line)
                if m:
                    levels = m.group(1)
                continue
            lines.append(line)
    for r in csv.DictReader(lines):
        if r["level"] == "all" and r["method"] in METHODS:
            rows.append(r)
    if not rows:
        sys.exit(f"chart_labels.py: {csv_path}: no rows of level 'all'")

    xs = [float(r["ns_per_step"]) for r in rows]
    xmin = 10 ** math.floor(math.log10(min(xs) / 1.2))
    xmax = 10 ** math.ceil(math.log10(max(xs) * 1.2))
    pen = [max(float(r["penetration_max"]), FLOOR) for r in rows]
    dev = [max(float(r["deviation_p99_frac"]), FLOOR) for r in rows]
    ranges = {1: (FLOOR / 2, 10 ** math.ceil(math.log10(max(pen) * 1.5))),
              2: (FLOOR / 2, 10 ** math.ceil(math.log10(max(dev) * 1.5)))}

    def to_page(panel, x, y):
        left, right = PANELS[panel]
        lo, hi = ranges[panel]
        fx = left + (math.log(x / xmin) / math.log(xmax / xmin)) * (right - left)
        fy = BOTTOM + (math.log(y / lo) / math.log(hi / lo)) * (TOP - BOTTOM)
        return fx * WIDTH, fy * HEIGHT

    def to_data(panel, px, py):
        left, right = PANELS[panel]
        lo, hi = ranges[panel]
        x = xmin * math.exp((px / WIDTH - left) / (right - left) * math.log(xmax / xmin))
        y = lo * math.exp((py / HEIGHT - BOTTOM) / (TOP - BOTTOM) * math.log(hi / lo))
        return x, y

    out_rows = []
    for panel in (1, 2):
        points, labels = [], []  # points: (px, py); labels: dict
        for r in rows:
            x = float(r["ns_per_step"])
            y = max(float(r["penetration_max"] if panel == 1 else r["deviation_p99_frac"]), FLOOR)
            px, py = to_page(panel, x, y)
            points.append((px, py))
            if panel == 1:  # the p99, at the floor for nearly every setting: a point too
                points.append(to_page(panel, x, max(float(r["penetration_p99"]), FLOOR)))
                if float(r["penetration_max"]) < FLOOR:
                    continue
            text = f'{short(r["knob"], r["value"])} {r["inside_solid"]}/{r["refused"]}'
            labels.append({"px": px, "py": py, "x": px + 7, "y": py, "w": CHAR_W * len(text) + 2,
                           "text": text, "method": METHODS.index(r["method"]),
                           "default": r["knob"] == "default"})
        left, right = PANELS[panel]
        low_y, high_y = BOTTOM * HEIGHT + LINE_H / 2, TOP * HEIGHT - LINE_H / 2
        # Vertical pushes until nothing overlaps: label against label, and
        # label against the points (which stay).
        for _ in range(2000):
            moved = False
            for i, a in enumerate(labels):
                for b in labels[i + 1:]:
                    if a["x"] < b["x"] + b["w"] and b["x"] < a["x"] + a["w"]:
                        gap = LINE_H - abs(a["y"] - b["y"])
                        if gap > 0:
                            up, down = (a, b) if (a["y"], id(a)) >= (b["y"], id(b)) else (b, a)
                            up["y"] += gap / 2 + 0.1
                            down["y"] -= gap / 2 + 0.1
                            moved = True
                for px, py in points:
                    if a["x"] - 3 < px < a["x"] + a["w"] and abs(a["y"] - py) < LINE_H / 2 + 2:
                        a["y"] += (1 if a["y"] >= a["py"] else -1) * 1.0
                        moved = True
                a["y"] = min(max(a["y"], low_y), high_y)
            if not moved:
                break
        for a in labels:
            x, y = to_data(panel, a["x"], a["y"])
            px, py = to_data(panel, a["px"], a["py"])
            text = a["text"].replace(",", " ")
            out_rows.append(f'{panel},{a["method"]},{px:.6g},{py:.6g},{x:.6g},{y:.6g},'
                            f'{text},{int(a["default"])}')
    with open(out + ".dat", "w") as f:
        f.write("\n".join(out_rows) + "\n")
    with open(out + ".gp", "w") as f:
        f.write(f"xmin = {xmin:g}; xmax = {xmax:g}\n")
        f.write(f"ymin1 = {ranges[1][0]:g}; ymax1 = {ranges[1][1]:g}\n")
        f.write(f"ymin2 = {ranges[2][0]:g}; ymax2 = {ranges[2][1]:g}\n")
        f.write(f"levels = '{levels}'\n")


if __name__ == "__main__":
    main()
