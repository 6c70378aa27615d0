#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Generate the small sample levels in samples/ and check them.

    python3 scripts/make_samples.py            # (re)write samples/*
    python3 scripts/make_samples.py --check    # verify the files in samples/
    python3 scripts/make_samples.py --out DIR  # write somewhere else

Every level is built only from closed convex solids (boxes and convex prisms),
written in the plain-geometry conventions of ../shared/levels:

  NAME.obj          one `o` group per solid, triangles wound counter-clockwise
                    seen from outside (outward normals); vertices are shared
                    only inside one solid, never between solids.
  NAME.brushes.txt  one solid a line, groups of `nx ny nz d` (unit outward
                    normal); p is inside when n.p < d for every plane.
  NAME.spawns.txt   player origins `x y z`, one a line.

Units are metres, Y is up. Standard library only; output is deterministic.
"""

import argparse
import math
import os
import sys

SCRIPT = "scripts/make_samples.py"

# A spawn is a player origin, as in ../shared/levels: a body's centre goes
# about 0.3 m above it.  A Quake 3 player origin sits 24 units (0.75 m) above
# the player's feet, so spawns are written 0.75 m above the floor surface; the
# body centre then starts at 1.05 m, clear of the floor for an ellipsoid of
# y radius 0.85 m.  Set to 0.0 to put the points exactly on the floor.
SPAWN_HEIGHT = 0.75

# The stand-in player of ../shared/levels/README.md, used by --check.
BODY_RADII = (0.45, 0.85, 0.45)
BODY_LIFT = 0.3

MAX_TRIANGLES = 2000


# --------------------------------------------------------------------------
# small vector helpers

def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def scale(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0])


def length(a):
    return math.sqrt(dot(a, a))


def normalize(a):
    n = length(a)
    return (a[0] / n, a[1] / n, a[2] / n)


def centroid(points):
    n = float(len(points))
    return (sum(p[0] for p in points) / n,
            sum(p[1] for p in points) / n,
            sum(p[2] for p in points) / n)


def rnd(x):
    """Round to the 5 decimals written to the .obj (and drop -0.0)."""
    v = round(x, 5)
    return v + 0.0 if v != 0 else 0.0


# --------------------------------------------------------------------------
# solids

class Solid:
    """A closed convex polyhedron: vertices and convex polygon faces."""

    def __init__(self, name, verts, faces):
        self.name = name
        self.verts = [tuple(rnd(c) for c in v) for v in verts]
        c = centroid(self.verts)
        self.faces = []
        for f in faces:
            n = newell(self.verts, f)
            fc = centroid([self.verts[i] for i in f])
            if dot(n, sub(fc, c)) < 0:       # orient counter-clockwise from outside
                f = list(reversed(f))
            self.faces.append(list(f))

    def triangles(self):
        for f in self.faces:
            for k in range(1, len(f) - 1):
                yield (f[0], f[k], f[k + 1])

    def planes(self):
        out = []
        for f in self.faces:
            n = normalize(newell(self.verts, f))
            d = sum(dot(n, self.verts[i]) for i in f) / len(f)
            out.append((n, d))
        return out


def newell(verts, face):
    """Polygon normal (not normalised) by Newell's method."""
    nx = ny = nz = 0.0
    for k in range(len(face)):
        a = verts[face[k]]
        b = verts[face[(k + 1) % len(face)]]
        nx += (a[1] - b[1]) * (a[2] + b[2])
        ny += (a[2] - b[2]) * (a[0] + b[0])
        nz += (a[0] - b[0]) * (a[1] + b[1])
    return (nx, ny, nz)


def prism(name, base, offset):
    """Extrude the convex planar polygon `base` (3D points, in order) by `offset`."""
    n = len(base)
    verts = list(base) + [add(p, offset) for p in base]
    faces = [list(range(n)), list(range(n, 2 * n))]
    for k in range(n):
        j = (k + 1) % n
        faces.append([k, j, n + j, n + k])
    return Solid(name, verts, faces)


def box(name, x0, x1, y0, y1, z0, z1):
    assert x0 < x1 and y0 < y1 and z0 < z1, name
    base = [(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)]
    return prism(name, base, (0.0, y1 - y0, 0.0))


def column(name, footprint_xz, y0, y1):
    """Vertical prism over a convex footprint given as (x, z) points."""
    base = [(x, y0, z) for (x, z) in footprint_xz]
    return prism(name, base, (0.0, y1 - y0, 0.0))


def octagon_pillar(name, cx, cz, r, y0, y1):
    """Regular octagonal prism, circumradius r, with faces facing +-x, +-z."""
    pts = []
    for k in range(8):
        a = math.radians(22.5 + 45.0 * k)
        pts.append((cx + r * math.cos(a), cz + r * math.sin(a)))
    return column(name, pts, y0, y1)


def wedge_z(name, x0, x1, z_low, z_high, y0, rise):
    """Ramp: triangular prism over x in [x0, x1]; the slope climbs from
    (y0 at z_low) to (y0 + rise at z_high), with a vertical face at z_high."""
    base = [(x0, y0, z_low), (x0, y0, z_high), (x0, y0 + rise, z_high)]
    return prism(name, base, (x1 - x0, 0.0, 0.0))


def wedge_x(name, z0, z1, x_low, x_high, y0, rise):
    """As wedge_z, climbing along x instead."""
    base = [(x_low, y0, z0), (x_high, y0, z0), (x_high, y0 + rise, z0)]
    return prism(name, base, (0.0, 0.0, z1 - z0))


# --------------------------------------------------------------------------
# levels

class Level:
    def __init__(self, name, summary):
        self.name = name
        self.summary = summary
        self.solids = []
        self.spawns = []

    def add(self, solid):
        assert all(s.name != solid.name for s in self.solids), solid.name
        self.solids.append(solid)

    def spawn(self, x, z, floor_y=0.0):
        self.spawns.append((x, floor_y + SPAWN_HEIGHT, z))


def make_arena():
    lv = Level("arena", "40 x 40 m arena: floor, perimeter walls, stairs, ramp "
               "to a platform, pillars, thin wall, V crease, low ceiling")
    H = 4.0   # perimeter wall height
    # floor slab: top at y = 0, 1 m thick
    lv.add(box("floor", -20, 20, -1, 0, -20, 20))
    # perimeter walls, 1 m thick, 4 m high; inner faces at x, z = +-19
    lv.add(box("wall_north", -20, 20, 0, H, 19, 20))
    lv.add(box("wall_south", -20, 20, 0, H, -20, -19))
    lv.add(box("wall_east", 19, 20, 0, H, -19, 19))
    lv.add(box("wall_west", -20, -19, 0, H, -19, 19))

    # raised platform in the south-west corner, top at 2.25 m
    lv.add(box("platform", -19, -14, 0, 2.25, -19, -14))
    # staircase along the south wall, climbing towards -x onto the platform:
    # 8 steps of 0.25 m rise and 0.4 m tread, 2 m wide
    for j in range(8):
        top = 2.0 - 0.25 * j
        x0 = -14 + 0.4 * j
        lv.add(box("stair_%d" % (8 - j), x0, x0 + 0.4, 0, top, -19, -17))
    # ramp onto the platform from the north: rise 2.25 m over 5.5 m (22.2 deg)
    lv.add(wedge_z("ramp", -19, -16, -8.5, -14, 0, 2.25))

    # pillars: four 1 x 1 x 4 m boxes around the open middle, two octagons
    for name, cx, cz in (("pillar_ne", 7, 7), ("pillar_nw", -7, 7),
                         ("pillar_se", 7, -7), ("pillar_sw", -7, -7)):
        lv.add(box(name, cx - 0.5, cx + 0.5, 0, H, cz - 0.5, cz + 0.5))
    lv.add(octagon_pillar("pillar_oct_n", 0, 12, 0.75, 0, H))
    lv.add(octagon_pillar("pillar_oct_s", 0, -12, 0.75, 0, H))

    # free-standing thin wall: 1 cm thick (x in [9.995, 10.005]), 3 m high,
    # 4 m long (z in [-2, 2])
    lv.add(box("thin_wall", 9.995, 10.005, 0, 3, -2, 2))

    # V crease: two 0.2 m thick, 3 m high vertical slabs whose inner faces
    # meet at the apex (-15, y, 0) at 30 degrees, the V opening towards +x.
    # Each slab is cut by the plane z = 0, where the two slabs touch.
    half = math.radians(15.0)
    apex = (-15.0, 0.0)
    arm, t = 4.0, 0.2
    back = (apex[0] - t / math.sin(half), 0.0)
    for name, s in (("crease_n", 1.0), ("crease_s", -1.0)):
        d = (math.cos(half), s * math.sin(half))        # along the inner face
        o = (-math.sin(half) * 1.0, s * math.cos(half))  # away from the V
        e = (apex[0] + arm * d[0], apex[1] + arm * d[1])
        e2 = (e[0] + t * o[0], e[1] + t * o[1])
        lv.add(column(name, [back, apex, e, e2], 0, 3))

    # low ceiling: a 0.3 m roof slab over the south-east corner, underside at
    # 1.9 m, resting on the east and south walls and on three pillars
    lv.add(box("roof", 12, 19, 1.9, 2.2, -19, -12))
    lv.add(box("roof_post_corner", 12, 12.4, 0, 1.9, -12.4, -12))
    lv.add(box("roof_post_west", 12, 12.4, 0, 1.9, -15.7, -15.3))
    lv.add(box("roof_post_north", 15.3, 15.7, 0, 1.9, -12.4, -12))

    for x, z in ((0, 0), (4, 4), (-4, -4), (15, 6), (-10, 8), (0, 16),
                 (-6, -14), (8, -14)):
        lv.spawn(x, z)
    return lv


def make_box_room():
    lv = Level("box_room", "closed room, 6 x 3 x 6 m inside, six 0.5 m slabs")
    t = 0.5
    lv.add(box("floor", -3 - t, 3 + t, -t, 0, -3 - t, 3 + t))
    lv.add(box("ceiling", -3 - t, 3 + t, 3, 3 + t, -3 - t, 3 + t))
    lv.add(box("wall_east", 3, 3 + t, 0, 3, -3 - t, 3 + t))
    lv.add(box("wall_west", -3 - t, -3, 0, 3, -3 - t, 3 + t))
    lv.add(box("wall_north", -3, 3, 0, 3, 3, 3 + t))
    lv.add(box("wall_south", -3, 3, 0, 3, -3 - t, -3))
    for x, z in ((0, 0), (1.5, 1.5), (-1.5, -1.5), (1.5, -1.5)):
        lv.spawn(x, z)
    return lv


def make_slopes():
    lv = Level("slopes", "floor with 30, 45 and 60 degree wedges side by side")
    lv.add(box("floor", -12, 12, -1, 0, -10, 10))
    rise = 2.0
    for name, x0, deg in (("slope_30", -8, 30), ("slope_45", -2, 45),
                          ("slope_60", 4, 60)):
        run = rise / math.tan(math.radians(deg))
        lv.add(wedge_z(name, x0, x0 + 4, 0, run, 0, rise))
    for x, z in ((-6, -4), (0, -4), (6, -4), (0, -8)):
        lv.spawn(x, z)
    return lv


LEVELS = (make_arena, make_box_room, make_slopes)


# --------------------------------------------------------------------------
# writing

def fmt_plane_num(x):
    v = round(x, 6)
    return "%.6f" % (v + 0.0 if v != 0 else 0.0)


def write_level(lv, out_dir):
    ntri = sum(len(list(s.triangles())) for s in lv.solids)
    assert ntri <= MAX_TRIANGLES, (lv.name, ntri)
    lines = ["# generated by %s: %s; %d solids, %d triangles"
             % (SCRIPT, lv.summary, len(lv.solids), ntri),
             "# units metres, Y up; closed convex solids, counter-clockwise "
             "from outside; regenerate with python3 %s" % SCRIPT]
    base = 1
    for s in lv.solids:
        lines.append("o %s" % s.name)
        for v in s.verts:
            lines.append("v %.5f %.5f %.5f" % v)
        for a, b, c in s.triangles():
            lines.append("f %d %d %d" % (a + base, b + base, c + base))
        base += len(s.verts)
    write(os.path.join(out_dir, lv.name + ".obj"), lines)

    blines = []
    for s in lv.solids:
        nums = []
        for n, d in s.planes():
            nums += [fmt_plane_num(n[0]), fmt_plane_num(n[1]),
                     fmt_plane_num(n[2]), fmt_plane_num(d)]
        blines.append(" ".join(nums))
    write(os.path.join(out_dir, lv.name + ".brushes.txt"), blines)

    write(os.path.join(out_dir, lv.name + ".spawns.txt"),
          ["%.4f %.4f %.4f" % tuple(c + 0.0 for c in p) for p in lv.spawns])
    return ntri


def write(path, lines):
    with open(path, "w", newline="\n") as f:
        f.write("\n".join(lines) + "\n")


# --------------------------------------------------------------------------
# checking (reads the written files back, independent of the generator)

def read_obj(path):
    verts, solids, header = [], [], None
    cur = None
    with open(path) as f:
        for ln in f:
            p = ln.split()
            if not p:
                continue
            if p[0] == "#":
                if header is None:
                    header = ln.strip()
            elif p[0] == "o":
                cur = {"name": p[1], "tris": [], "first": len(verts)}
                solids.append(cur)
            elif p[0] == "v":
                verts.append(tuple(float(c) for c in p[1:4]))
            elif p[0] == "f":
                assert cur is not None, "face before any 'o' in " + path
                idx = [int(c) - 1 for c in p[1:]]
                assert len(idx) == 3, "non-triangle face in " + path
                cur["tris"].append(idx)
    for i, s in enumerate(solids):
        s["last"] = solids[i + 1]["first"] if i + 1 < len(solids) else len(verts)
    return header, verts, solids


def read_brushes(path):
    out = []
    with open(path) as f:
        for ln in f:
            v = [float(x) for x in ln.split()]
            assert v and len(v) % 4 == 0, "bad brush line in " + path
            out.append([((v[i], v[i + 1], v[i + 2]), v[i + 3])
                        for i in range(0, len(v), 4)])
    return out


def read_spawns(path):
    with open(path) as f:
        return [tuple(float(x) for x in ln.split()) for ln in f if ln.strip()]


def inside_strict(brush, p, eps=1e-6):
    return all(dot(n, p) < d - eps for n, d in brush)


def ellipsoid_clear(brush, c, radii):
    """Conservative: some brush plane separates the ellipsoid from the brush."""
    for n, d in brush:
        h = math.sqrt((radii[0] * n[0]) ** 2 + (radii[1] * n[1]) ** 2 +
                      (radii[2] * n[2]) ** 2)
        if dot(n, c) - h >= d - 1e-6:
            return True
    return False


def drop_distance(brushes, p):
    """Distance straight down from p to the first brush surface (or None)."""
    best = None
    down = (0.0, -1.0, 0.0)
    for b in brushes:
        lo, hi = 0.0, 1e3
        for n, d in b:
            den = dot(n, down)
            dist = d - dot(n, p)
            if abs(den) < 1e-12:
                if dist <= 0:
                    lo, hi = 1.0, 0.0
                    break
            elif den > 0:
                hi = min(hi, dist / den)
            else:
                lo = max(lo, dist / den)
        if lo < hi and (best is None or lo < best):
            best = lo
    return best


def sat_overlap(va, vb, axes, eps=1e-5):
    """True when no axis separates the two vertex sets (touching separates)."""
    for ax in axes:
        pa = [dot(ax, v) for v in va]
        pb = [dot(ax, v) for v in vb]
        if max(pa) <= min(pb) + eps or max(pb) <= min(pa) + eps:
            return False
    return True


def check_level(out_dir, name):
    errors = []

    def err(msg):
        errors.append("%s: %s" % (name, msg))

    header, verts, solids = read_obj(os.path.join(out_dir, name + ".obj"))
    brushes = read_brushes(os.path.join(out_dir, name + ".brushes.txt"))
    spawns = read_spawns(os.path.join(out_dir, name + ".spawns.txt"))
    if not header or SCRIPT not in header:
        err("first line is not the generator comment")
    if len(brushes) != len(solids):
        err("%d brush lines for %d solids" % (len(brushes), len(solids)))
    ntri = 0
    info = []   # per solid: (vertex list, unit triangle normals, edge dirs)
    for si, s in enumerate(solids):
        tag = "solid %s" % s["name"]
        tris = s["tris"]
        ntri += len(tris)
        for t in tris:
            if any(i < s["first"] or i >= s["last"] for i in t):
                err(tag + ": face uses a vertex of another solid")
        sv = verts[s["first"]:s["last"]]
        c = centroid(sv)
        # closed: every directed edge once, its reverse once (by position)
        edges = {}
        for t in tris:
            for k in range(3):
                a, b = verts[t[k]], verts[t[(k + 1) % 3]]
                edges[(a, b)] = edges.get((a, b), 0) + 1
        for (a, b), cnt in edges.items():
            if cnt != 1 or edges.get((b, a), 0) != 1:
                err(tag + ": edge %s-%s not shared by exactly two triangles "
                    "in opposite directions" % (a, b))
                break
        normals = []
        for t in tris:
            a, b, cc = verts[t[0]], verts[t[1]], verts[t[2]]
            n = cross(sub(b, a), sub(cc, a))
            if length(n) < 1e-9:
                err(tag + ": degenerate triangle")
                continue
            n = normalize(n)
            normals.append(n)
            if dot(n, sub(centroid([a, b, cc]), c)) <= 0:
                err(tag + ": triangle normal points into the solid")
        dirs = []
        for (a, b) in edges:
            e = sub(b, a)
            if length(e) > 1e-9:
                dirs.append(normalize(e))
        info.append((sv, normals, dirs))
        if si >= len(brushes):
            continue
        planes = brushes[si]
        for n, d in planes:
            if abs(length(n) - 1.0) > 1e-5:
                err(tag + ": plane normal not unit")
            if any(dot(n, v) > d + 1e-4 for v in sv):
                err(tag + ": a vertex lies outside plane %s %g" % (n, d))
        used = [False] * len(planes)
        for t in tris:
            tv = [verts[i] for i in t]
            tn = normalize(cross(sub(tv[1], tv[0]), sub(tv[2], tv[0])))
            hit = False
            for k, (n, d) in enumerate(planes):
                if all(abs(dot(n, v) - d) <= 1e-4 for v in tv) and dot(n, tn) > 0.999:
                    used[k] = hit = True
            if not hit:
                err(tag + ": triangle lies on none of its brush planes")
        if not all(used):
            err(tag + ": brush plane with no triangle on it")
    if ntri > MAX_TRIANGLES:
        err("%d triangles, over %d" % (ntri, MAX_TRIANGLES))

    # solids may touch but must not overlap
    boxes = []
    for sv, _, _ in info:
        boxes.append([(min(v[k] for v in sv), max(v[k] for v in sv)) for k in range(3)])
    for i in range(len(info)):
        for j in range(i + 1, len(info)):
            if any(boxes[i][k][1] <= boxes[j][k][0] + 1e-5 or
                   boxes[j][k][1] <= boxes[i][k][0] + 1e-5 for k in range(3)):
                continue
            axes = dedupe(info[i][1] + info[j][1] +
                          [normalize(cross(a, b)) for a in dedupe(info[i][2])
                           for b in dedupe(info[j][2])
                           if length(cross(a, b)) > 1e-6])
            if sat_overlap(info[i][0], info[j][0], axes):
                err("solids %s and %s overlap" % (solids[i]["name"], solids[j]["name"]))

    # spawns: outside every brush, body fits, SPAWN_HEIGHT above a floor
    for p in spawns:
        for bi, b in enumerate(brushes):
            if inside_strict(b, p):
                err("spawn %s inside brush %s" % (p, solids[bi]["name"]))
        body = (p[0], p[1] + BODY_LIFT, p[2])
        for bi, b in enumerate(brushes):
            if not ellipsoid_clear(b, body, BODY_RADII):
                err("body at spawn %s may touch %s" % (p, solids[bi]["name"]))
        h = drop_distance(brushes, p)
        if h is None or abs(h - SPAWN_HEIGHT) > 1e-4:
            err("spawn %s is %s m above the floor, not %g" % (p, h, SPAWN_HEIGHT))
    return len(solids), ntri, len(spawns), errors


def dedupe(vectors):
    seen, out = set(), []
    for v in vectors:
        if v[0] < -1e-9 or (abs(v[0]) <= 1e-9 and (v[1] < -1e-9 or
                                                   (abs(v[1]) <= 1e-9 and v[2] < 0))):
            v = scale(v, -1.0)
        key = tuple(round(c, 6) + 0.0 for c in v)
        if key not in seen:
            seen.add(key)
            out.append(v)
    return out


# --------------------------------------------------------------------------

def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=os.path.join(root, "samples"),
                    help="output folder (default: samples/ of the project)")
    ap.add_argument("--check", action="store_true",
                    help="only verify the files already in the output folder")
    args = ap.parse_args()

    levels = [make() for make in LEVELS]
    if not args.check:
        os.makedirs(args.out, exist_ok=True)
        for lv in levels:
            ntri = write_level(lv, args.out)
            print("wrote %s/%s.{obj,brushes.txt,spawns.txt}: %d solids, %d triangles"
                  % (os.path.relpath(args.out), lv.name, len(lv.solids), ntri))
        return 0

    failed = False
    print("%-10s %7s %10s %7s" % ("level", "solids", "triangles", "spawns"))
    for lv in levels:
        ns, nt, nsp, errors = check_level(args.out, lv.name)
        print("%-10s %7d %10d %7d  %s" % (lv.name, ns, nt, nsp,
                                           "ok" if not errors else "FAILED"))
        for e in errors[:20]:
            print("  " + e)
        failed = failed or bool(errors)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
