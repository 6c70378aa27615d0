#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Generate detailed levels that are not brush-built, for the benchmarks.

    python3 scripts/make_detailed_levels.py --out DIR            # full size
    python3 scripts/make_detailed_levels.py --out DIR --small    # a few thousand triangles each
    python3 scripts/make_detailed_levels.py --check --bspc build/compiler/bspc [--walkers W]

The shared OpenArena levels are built from brushes: a few large convex solids.
Levels made in a modelling or CAD tool look different, and cost the BSP tree
differently; these three stand in for them:

  terrain       a heightfield (316 x 316 cells of 1 m, 2 triangles each: about
                200k triangles): smooth hills from sine waves and gaussian
                bumps, and mesas whose edges are cliffs one cell wide; a wall
                around the edge keeps walkers on it.  One open surface, facing up.
  curved_room   a round hall of finely tessellated curved surfaces: a gently
                rolling floor, a cylindrical wall and a dome facing into the
                hall, round columns and arches (closed solids facing out).
  cad_building  a three-storey building assembled CAD style from thousands of
                small boxes that intersect and share coincident faces: floor
                tiles, pillars, beams, wall piers, sills, lintels, window
                frames, stairs, desks, on a ground slab.

Each level is NAME.obj (counter-clockwise seen from the front, the convention
of ../shared/levels: normals point into free space) and NAME.spawns.txt
(player origins, 0.75 m above walkable floor: a body's centre goes 0.3 m above
them, as for the shared levels).  cad_building, made of convex boxes only,
also gets NAME.brushes.txt (the brush oracle's format), so walkers can count
agents inside a solid.  The same options give the same bytes.

--check generates the small levels into a temporary folder (or --out) and
verifies them: every triangle has an area, every spawn is inside the level's
bounds, the body at every spawn touches no triangle, and the first triangle
straight below every spawn is walkable floor seen from the front; then it
compiles each with bspc (which must succeed) and, with --walkers, runs a short
crowd from the spawns (which must succeed and keep every agent in the level).
Standard library only.
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import make_samples as samples  # noqa: E402  (vector helpers, convex solids, writers)
from make_samples import add, cross, dot, length, normalize, sub  # noqa: E402

SCRIPT = "scripts/make_detailed_levels.py"
# The walkable limit of the runtime's default settings and of walkers'
# floor placement: 45 degrees from horizontal.
WALKABLE_NORMAL_Y = math.cos(math.radians(45.0))


class Mesh:
    """A level under construction: a triangle soup with `o` groups, and the
    brushes of the groups that are convex solids."""

    def __init__(self, name, summary):
        self.name = name
        self.summary = summary
        self.verts = []
        self.tris = []
        self.groups = []  # (name, first triangle)
        self.brushes = []
        self.spawns = []

    def group(self, name):
        self.groups.append((name, len(self.tris)))

    def vertex(self, p):
        self.verts.append(tuple(samples.rnd(c) for c in p))
        return len(self.verts) - 1

    def triangle(self, a, b, c, facing):
        """Adds the triangle of vertex indices a, b, c wound so its normal
        points along `facing` (the side free space is on)."""
        pa, pb, pc = self.verts[a], self.verts[b], self.verts[c]
        if dot(cross(sub(pb, pa), sub(pc, pa)), facing) < 0:
            b, c = c, b
        self.tris.append((a, b, c))

    def quad(self, a, b, c, d, facing):
        """Adds the quad a-b-c-d (in order around it) as two triangles."""
        self.triangle(a, b, c, facing)
        self.triangle(a, c, d, facing)

    def solid(self, solid):
        """Adds a closed convex solid (make_samples.Solid: outward normals)."""
        self.group(solid.name)
        base = len(self.verts)
        self.verts.extend(solid.verts)
        self.tris.extend((a + base, b + base, c + base) for a, b, c in solid.triangles())
        self.brushes.append(solid.planes())

    def spawn(self, x, floor_y, z):
        self.spawns.append((x, floor_y + samples.SPAWN_HEIGHT, z))


def hexahedron(name, corners):
    """A convex solid from 8 corners indexed by bits: corner i + 2j + 4k."""
    faces = []
    for bit in (1, 2, 4):
        p, q = [b for b in (1, 2, 4) if b != bit]
        for side in (0, bit):
            faces.append([side, side + p, side + p + q, side + q])
    return samples.Solid(name, corners, faces)


def box(name, lo, hi):
    return samples.box(name, lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])


# --------------------------------------------------------------------------
# terrain


def make_terrain(small):
    cells = 24 if small else 316
    spacing = 1.0
    size = cells * spacing
    m = Mesh("terrain", "%d x %d cell heightfield, %g m cells: hills, mesas with cliffs, "
             "a wall around the edge" % (cells, cells, spacing))
    # Mesas: (centre x, centre z as fractions of the size, radius fraction, height m).
    mesas = [(0.25, 0.3, 0.08, 4.0), (0.7, 0.65, 0.1, 3.0), (0.35, 0.75, 0.06, 5.0),
             (0.8, 0.2, 0.07, 2.5)]
    # Bumps: (x, z fractions, height m, width fraction).
    bumps = [(0.5, 0.5, 6.0, 0.15), (0.15, 0.8, 4.0, 0.1), (0.85, 0.85, -3.0, 0.12),
             (0.6, 0.15, 5.0, 0.09)]

    # Bumps and mesas are as tall on a small terrain as on a large one would
    # be too steep to walk: they shrink with it.
    relief = min(1.0, size / 100.0)

    def height(x, z):
        h = 1.5 * math.sin(x / 17.0) * math.cos(z / 23.0) + 0.7 * math.sin((x + 2 * z) / 9.0)
        for bx, bz, bh, bw in bumps:
            d2 = (x - bx * size) ** 2 + (z - bz * size) ** 2
            h += relief * bh * math.exp(-d2 / (2 * (bw * size) ** 2))
        for mx, mz, mr, mh in mesas:
            # The rise happens within half a cell of the rim, so each rim is
            # a band of cells as steep as a cliff.
            d = math.hypot(x - mx * size, z - mz * size) - mr * size
            h += relief * mh * min(1.0, max(0.0, 0.5 - d / (0.5 * spacing)))
        return h

    m.group("ground")
    n = cells + 1
    heights = [[height(i * spacing, j * spacing) for j in range(n)] for i in range(n)]
    for i in range(n):
        for j in range(n):
            m.vertex((i * spacing, heights[i][j], j * spacing))
    up = (0.0, 1.0, 0.0)
    for i in range(cells):
        for j in range(cells):
            v00, v10 = i * n + j, (i + 1) * n + j
            v01, v11 = v00 + 1, v10 + 1
            m.triangle(v00, v01, v10, up)
            m.triangle(v10, v01, v11, up)

    # The wall: vertical panels along each edge, facing in, from below the
    # lowest ground to above the highest.
    low = min(min(r) for r in heights) - 2.0
    high = max(max(r) for r in heights) + 4.0
    m.group("edge_wall")
    panel = 8.0
    panels = max(1, int(round(size / panel)))
    for corner, along, inward in (((0, 0), (1, 0), (0, 1)), ((0, size), (1, 0), (0, -1)),
                                  ((0, 0), (0, 1), (1, 0)), ((size, 0), (0, 1), (-1, 0))):
        for k in range(panels):
            x0 = corner[0] + along[0] * size * k / panels
            z0 = corner[1] + along[1] * size * k / panels
            x1 = corner[0] + along[0] * size * (k + 1) / panels
            z1 = corner[1] + along[1] * size * (k + 1) / panels
            a = m.vertex((x0, low, z0))
            b = m.vertex((x1, low, z1))
            c = m.vertex((x1, high, z1))
            d = m.vertex((x0, high, z0))
            m.quad(a, b, c, d, (inward[0], 0.0, inward[1]))

    # Spawns on a ring around the middle, at grid vertices whose neighbouring
    # cells are walkable, moved inwards until they are.
    def walkable(i, j):
        h = heights[i][j]
        return all(abs(heights[i + di][j + dj] - h) < 0.8 * spacing
                   for di in (-2, -1, 0, 1, 2) for dj in (-2, -1, 0, 1, 2))

    centre = cells // 2
    for k in range(16):
        angle = 2 * math.pi * k / 16
        for r in range(int(0.35 * cells), 1, -1):
            i = centre + int(round(r * math.cos(angle)))
            j = centre + int(round(r * math.sin(angle)))
            if 2 <= i < cells - 2 and 2 <= j < cells - 2 and walkable(i, j):
                m.spawn(i * spacing, heights[i][j], j * spacing)
                break
    return m


# --------------------------------------------------------------------------
# curved room


def make_curved_room(small):
    radius = 9.0 if small else 20.0
    segments = 32 if small else 192
    wall_height = 6.0
    m = Mesh("curved_room", "round hall of radius %g m, %d segments around: rolling floor, "
             "cylindrical wall, dome, round columns, arches" % (radius, segments))

    def floor_y(r, angle):
        return 0.15 * math.sin(0.8 * r) * math.cos(3 * angle)

    def ring(n, r, angle_of, y_of):
        return [m.vertex((r * math.cos(angle_of(k)), y_of(k), r * math.sin(angle_of(k))))
                for k in range(n)]

    angle = [2 * math.pi * k / segments for k in range(segments)]

    # Floor: rings of quads around a centre fan, facing up.
    m.group("floor")
    rings = max(4, int(radius / (0.4 if not small else 1.0)))
    up = (0.0, 1.0, 0.0)
    centre = m.vertex((0.0, floor_y(0.0, 0.0), 0.0))
    previous = None
    for q in range(1, rings + 1):
        r = radius * q / rings
        current = ring(segments, r, lambda k: angle[k], lambda k, r=r: floor_y(r, angle[k]))
        for k in range(segments):
            k1 = (k + 1) % segments
            if previous is None:
                m.triangle(centre, current[k], current[k1], up)
            else:
                m.quad(previous[k], current[k], current[k1], previous[k1], up)
        previous = current

    # Wall: a cylinder facing the axis, from below the floor to the dome.
    m.group("wall")
    wall_rings = 12 if not small else 3
    rows = [ring(segments, radius, lambda k: angle[k],
                 lambda k, y=-0.5 + (wall_height + 0.5) * q / wall_rings: y)
            for q in range(wall_rings + 1)]
    for lower, upper in zip(rows, rows[1:]):
        for k in range(segments):
            k1 = (k + 1) % segments
            inward = (-math.cos(angle[k] + math.pi / segments), 0.0,
                      -math.sin(angle[k] + math.pi / segments))
            m.quad(lower[k], lower[k1], upper[k1], upper[k], inward)

    # Dome: a hemisphere on the wall, facing its centre.
    m.group("dome")
    latitudes = segments // 4
    top = (0.0, wall_height, 0.0)
    previous = rows[-1]
    for q in range(1, latitudes):
        phi = 0.5 * math.pi * q / latitudes
        current = ring(segments, radius * math.cos(phi), lambda k: angle[k],
                       lambda k, phi=phi: wall_height + radius * math.sin(phi))
        for k in range(segments):
            k1 = (k + 1) % segments
            mid = m.verts[previous[k]]
            m.quad(previous[k], previous[k1], current[k1], current[k], sub(top, mid))
        previous = current
    pole = m.vertex((0.0, wall_height + radius, 0.0))
    for k in range(segments):
        m.triangle(previous[k], previous[(k + 1) % segments], pole, (0.0, -1.0, 0.0))

    # Columns: round prisms standing in the floor, up to 4 m.
    columns = 6
    column_sides = 48 if not small else 12
    column_radius = 0.5
    for c in range(columns):
        a = 2 * math.pi * (c + 0.5) / columns
        cx, cz = 0.5 * radius * math.cos(a), 0.5 * radius * math.sin(a)
        footprint = [(cx + column_radius * math.cos(2 * math.pi * k / column_sides),
                      cz + column_radius * math.sin(2 * math.pi * k / column_sides))
                     for k in range(column_sides)]
        m.solid(samples.column("column%d" % c, footprint, -0.5, 4.0))

    # Arches: gates standing on the floor across the hall's outer ring, each a
    # half ring of convex segments (rectangular section) on two legs.
    arches = 4
    arch_segments = 24 if not small else 6
    arch_radius, half_width, half_depth = 2.2, 0.25, 0.3
    spring = 0.6  # height of the arch's centre above y = 0
    for g in range(arches):
        a = 2 * math.pi * g / arches
        gx, gz = 0.78 * radius * math.cos(a), 0.78 * radius * math.sin(a)
        span = (-math.sin(a), 0.0, math.cos(a))  # the gate's plane holds span and up
        depth = (math.cos(a), 0.0, math.sin(a))

        def point(theta, r, d, gx=gx, gz=gz, span=span, depth=depth):
            s, y = r * math.cos(theta), spring + r * math.sin(theta)
            return (gx + s * span[0] + d * depth[0], y, gz + s * span[2] + d * depth[2])

        for s in range(arch_segments):
            t0 = math.pi * s / arch_segments
            t1 = math.pi * (s + 1) / arch_segments
            corners = [point((t0, t1)[i & 1], arch_radius + ((i >> 1) & 1 and half_width or
                                                             -half_width),
                             half_depth if i & 4 else -half_depth) for i in range(8)]
            m.solid(hexahedron("arch%d_%d" % (g, s), corners))
        for side, theta in (("a", 0.0), ("b", math.pi)):
            corners = [point(theta, arch_radius + (half_width if (i >> 1) & 1 else -half_width),
                             half_depth if i & 4 else -half_depth) for i in range(8)]
            for i in range(8):  # the leg reaches from below the floor up to the spring
                if not i & 1:
                    corners[i] = (corners[i][0], -0.5, corners[i][2])
            m.solid(hexahedron("arch%d_leg_%s" % (g, side), corners))

    # Spawns between the columns and the arches.
    for k in range(12):
        a = 2 * math.pi * k / 12
        for r in (0.3 * radius, 0.62 * radius):
            m.spawn(r * math.cos(a), floor_y(r, a) + 0.05, r * math.sin(a))
    return m


# --------------------------------------------------------------------------
# CAD building

STOREY = 3.0
SLAB = 0.3
WALL = 0.25


def make_cad_building(small):
    storeys = 2 if small else 3
    width, depth = (12.0, 12.0) if small else (36.0, 24.0)
    bay = 6.0
    m = Mesh("cad_building", "%d-storey %g x %g m building of small intersecting boxes" %
             (storeys, width, depth))
    count = [0]

    def part(kind, lo, hi):
        count[0] += 1
        m.solid(box("%s%d" % (kind, count[0]), lo, hi))

    # The site: a ground slab around the building.
    part("site", (-10.0, -1.0, -10.0), (width + 10.0, 0.0, depth + 10.0))

    # Stairs in the first bay's corner: a flight along x from each storey.
    stair_x, stair_z, stair_width = 1.0, 1.0, 1.2
    steps, rise, tread = 15, STOREY / 15, 0.3

    def in_stairwell(x0, z0, x1, z1):
        return (x0 < stair_x + steps * tread + 0.5 and x1 > stair_x - 0.5 and
                z0 < stair_z + stair_width + 0.3 and z1 > stair_z - 0.3)

    tile = 2.0
    for s in range(storeys + 1):
        y = s * STOREY
        # Floor tiles (the roof on top): coincident faces between neighbours;
        # upper floors leave the stairwell open.
        for i in range(int(width / tile)):
            for j in range(int(depth / tile)):
                x0, z0 = i * tile, j * tile
                if s > 0 and in_stairwell(x0, z0, x0 + tile, z0 + tile):
                    continue
                part("tile", (x0, y - SLAB if s else y - 0.05, z0),
                     (x0 + tile, y if s else y + 0.05, z0 + tile))
        if s == storeys:
            break
        # Pillars through the slab above, beams under it into the pillars.
        for i in range(int(width / bay) + 1):
            for j in range(int(depth / bay) + 1):
                px = min(max(i * bay, 0.3), width - 0.3)
                pz = min(max(j * bay, 0.3), depth - 0.3)
                part("pillar", (px - 0.2, y, pz - 0.2), (px + 0.2, y + STOREY, pz + 0.2))
        for j in range(int(depth / bay) + 1):
            pz = min(max(j * bay, 0.3), depth - 0.3)
            for i in range(int(width / bay)):
                part("beam", (i * bay, y + STOREY - SLAB - 0.35, pz - 0.15),
                     ((i + 1) * bay, y + STOREY - 0.1, pz + 0.15))
        for i in range(int(width / bay) + 1):
            px = min(max(i * bay, 0.3), width - 0.3)
            for j in range(int(depth / bay)):
                part("beam", (px - 0.15, y + STOREY - SLAB - 0.35, j * bay),
                     (px + 0.15, y + STOREY - 0.1, (j + 1) * bay))
        # Outer walls, bay by 2 m bay: pier, sill, lintel, a window frame of
        # four thin boxes and a mullion, all touching or overlapping. The
        # ground floor has a door in the middle of the front.
        for side in range(4):
            along = width if side < 2 else depth
            for k in range(int(along / 2.0)):
                a0, a1 = k * 2.0, k * 2.0 + 2.0
                door = s == 0 and side == 0 and k == int(along / 4.0)

                def wall_box(kind, t0, t1, y0, y1, inset=0.0, side=side):
                    w0, w1 = -WALL / 2 + inset, WALL / 2 - inset
                    if side < 2:
                        z = 0.0 if side == 0 else depth
                        part(kind, (t0, y + y0, z + w0), (t1, y + y1, z + w1))
                    else:
                        x = 0.0 if side == 2 else width
                        part(kind, (x + w0, y + y0, t0), (x + w1, y + y1, t1))

                wall_box("pier", a0, a0 + 0.5, 0.0, STOREY)
                lintel = 2.1
                wall_box("lintel", a0 + 0.5, a1, lintel, STOREY)
                if door:
                    continue
                wall_box("sill", a0 + 0.5, a1, 0.0, 0.9)
                f = 0.06
                wall_box("frame", a0 + 0.5, a1, 0.9, 0.9 + f, 0.05)
                wall_box("frame", a0 + 0.5, a1, lintel - f, lintel, 0.05)
                wall_box("frame", a0 + 0.5, a0 + 0.5 + f, 0.9, lintel, 0.05)
                wall_box("frame", a1 - f, a1, 0.9, lintel, 0.05)
                mid = 0.5 * (a0 + 0.5 + a1)
                wall_box("mullion", mid - f / 2, mid + f / 2, 0.9, lintel, 0.07)
        # An inner partition across the middle, a door in every bay.
        px = width / 2
        for j in range(int(depth / bay)):
            z0, z1 = j * bay, (j + 1) * bay
            part("partition", (px - 0.06, y, z0), (px + 0.06, y + STOREY - SLAB, z0 + 2.0))
            part("partition", (px - 0.06, y, z0 + 3.0), (px + 0.06, y + STOREY - SLAB, z1))
            part("doorhead", (px - 0.08, y + 2.1, z0 + 2.0), (px + 0.08, y + STOREY - SLAB, z0 + 3.0))
        # The flight up to the next storey: each step a box from the floor,
        # overlapping the one before; a stringer and a rail beside it.
        for k in range(steps):
            part("step", (stair_x + k * tread, y, stair_z),
                 (stair_x + (k + 2) * tread, y + (k + 1) * rise, stair_z + stair_width))
        part("stringer", (stair_x, y, stair_z + stair_width),
             (stair_x + (steps + 1) * tread, y + STOREY, stair_z + stair_width + 0.1))
        for k in range(0, steps, 3):
            part("baluster", (stair_x + k * tread, y + (k + 1) * rise, stair_z + stair_width + 0.1),
                 (stair_x + k * tread + 0.04, y + (k + 1) * rise + 1.0,
                  stair_z + stair_width + 0.14))
        # Desks (a top on four legs) in the middle of every bay's far half.
        for i in range(int(width / bay)):
            for j in range(int(depth / bay)):
                dx, dz = i * bay + 3.0, j * bay + 4.3
                if in_stairwell(dx - 1, dz - 1, dx + 1, dz + 1):
                    continue
                part("desktop", (dx - 0.6, y + 0.72, dz - 0.35), (dx + 0.6, y + 0.76, dz + 0.35))
                for lx in (-0.55, 0.5):
                    for lz in (-0.3, 0.25):
                        part("leg", (dx + lx, y, dz + lz), (dx + lx + 0.05, y + 0.72, dz + lz + 0.05))

    # Spawns in the open half of every bay, on every storey, off the stairs.
    for s in range(storeys):
        for i in range(int(width / bay)):
            for j in range(int(depth / bay)):
                x, z = i * bay + 3.0, j * bay + 1.7
                if not in_stairwell(x - 1, z - 1, x + 1, z + 1):
                    m.spawn(x, s * STOREY + (0.05 if s == 0 else 0.0), z)
    return m


LEVELS = (make_terrain, make_curved_room, make_cad_building)


# --------------------------------------------------------------------------
# writing


def write_level(m, out_dir):
    lines = ["# generated by %s: %s; %d triangles" % (SCRIPT, m.summary, len(m.tris)),
             "# units metres, Y up; counter-clockwise seen from the front (normals point "
             "into free space)"]
    lines += ["v %.5f %.5f %.5f" % v for v in m.verts]
    starts = dict((first, name) for name, first in m.groups)
    for t, (a, b, c) in enumerate(m.tris):
        if t in starts:
            lines.append("o %s" % starts[t])
        lines.append("f %d %d %d" % (a + 1, b + 1, c + 1))
    samples.write(os.path.join(out_dir, m.name + ".obj"), lines)
    samples.write(os.path.join(out_dir, m.name + ".spawns.txt"),
                  ["%.4f %.4f %.4f" % tuple(c + 0.0 for c in p) for p in m.spawns])
    brushes = os.path.join(out_dir, m.name + ".brushes.txt")
    if m.brushes and len(m.brushes) == len(m.groups):
        samples.write(brushes, [" ".join(samples.fmt_plane_num(x) for n, d in planes
                                         for x in (n[0], n[1], n[2], d))
                                for planes in m.brushes])


# --------------------------------------------------------------------------
# checking


def closest_on_triangle(p, a, b, c):
    """The point of triangle abc nearest to p (Ericson's regions)."""
    ab, ac, ap = sub(b, a), sub(c, a), sub(p, a)
    d1, d2 = dot(ab, ap), dot(ac, ap)
    if d1 <= 0 and d2 <= 0:
        return a
    bp = sub(p, b)
    d3, d4 = dot(ab, bp), dot(ac, bp)
    if d3 >= 0 and d4 <= d3:
        return b
    vc = d1 * d4 - d3 * d2
    if vc <= 0 and d1 >= 0 and d3 <= 0:
        return add(a, samples.scale(ab, d1 / (d1 - d3)))
    cp = sub(p, c)
    d5, d6 = dot(ab, cp), dot(ac, cp)
    if d6 >= 0 and d5 <= d6:
        return c
    vb = d5 * d2 - d1 * d6
    if vb <= 0 and d2 >= 0 and d6 <= 0:
        return add(a, samples.scale(ac, d2 / (d2 - d6)))
    va = d3 * d6 - d5 * d4
    if va <= 0 and d4 - d3 >= 0 and d5 - d6 >= 0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return add(b, samples.scale(sub(c, b), w))
    denom = 1.0 / (va + vb + vc)
    return add(a, add(samples.scale(ab, vb * denom), samples.scale(ac, vc * denom)))


def first_below(p, triangles):
    """(distance, triangle) of the first triangle straight below p, or None."""
    best = None
    for t in triangles:
        a, b, c = t
        # 2D barycentric in xz.
        det = (b[0] - a[0]) * (c[2] - a[2]) - (c[0] - a[0]) * (b[2] - a[2])
        if abs(det) < 1e-12:
            continue
        u = ((p[0] - a[0]) * (c[2] - a[2]) - (c[0] - a[0]) * (p[2] - a[2])) / det
        v = ((b[0] - a[0]) * (p[2] - a[2]) - (p[0] - a[0]) * (b[2] - a[2])) / det
        if u < 0 or v < 0 or u + v > 1:
            continue
        y = a[1] + u * (b[1] - a[1]) + v * (c[1] - a[1])
        if y <= p[1] and (best is None or p[1] - y < best[0]):
            best = (p[1] - y, t)
    return best


def check_level(out_dir, name):
    """The errors found in the written level `name` (read back from files)."""
    errors = []
    verts, tris = [], []
    with open(os.path.join(out_dir, name + ".obj")) as f:
        for line in f:
            p = line.split()
            if p and p[0] == "v":
                verts.append(tuple(float(x) for x in p[1:4]))
            elif p and p[0] == "f":
                tris.append(tuple(verts[int(x) - 1] for x in p[1:4]))
    spawns = samples.read_spawns(os.path.join(out_dir, name + ".spawns.txt"))
    low = [min(v[k] for v in verts) for k in range(3)]
    high = [max(v[k] for v in verts) for k in range(3)]
    if not spawns:
        errors.append("no spawn")
    for t in tris:
        if length(cross(sub(t[1], t[0]), sub(t[2], t[0]))) < 1e-9:
            errors.append("degenerate triangle %s" % (t,))
            break
    radii = samples.BODY_RADII
    for p in spawns:
        if not all(low[k] < p[k] < high[k] for k in range(3)):
            errors.append("spawn %s outside the bounds %s - %s" % (p, low, high))
            continue
        centre = (p[0], p[1] + samples.BODY_LIFT, p[2])

        def unit(q):
            return tuple((q[k] - centre[k]) / radii[k] for k in range(3))

        for t in tris:
            if any(min(v[k] for v in t) > centre[k] + radii[k] or
                   max(v[k] for v in t) < centre[k] - radii[k] for k in range(3)):
                continue
            q = closest_on_triangle((0.0, 0.0, 0.0), *[unit(v) for v in t])
            if dot(q, q) <= 1.0:
                errors.append("the body at spawn %s touches triangle %s" % (p, t))
                break
        below = first_below(p, tris)
        if below is None:
            errors.append("no floor below spawn %s" % (p,))
            continue
        a, b, c = below[1]
        normal = normalize(cross(sub(b, a), sub(c, a)))
        if normal[1] < WALKABLE_NORMAL_Y:
            errors.append("the floor below spawn %s is not walkable from above (normal %s)" %
                          (p, normal))
    return len(tris), len(spawns), errors


def run_check(args):
    out = args.out or tempfile.mkdtemp(prefix="detailed_levels_")
    os.makedirs(out, exist_ok=True)
    failed = False
    print("%-13s %9s %7s" % ("level", "triangles", "spawns"))
    for make in LEVELS:
        m = make(True)
        write_level(m, out)
        ntri, nspawns, errors = check_level(out, m.name)
        obj = os.path.join(out, m.name + ".obj")
        blob = os.path.join(out, m.name + ".bspf")
        if args.bspc:
            run = subprocess.run([args.bspc, "-q", obj, "-o", blob], capture_output=True,
                                 text=True)
            if run.returncode != 0 or not os.path.exists(blob):
                errors.append("bspc failed: %s" % run.stderr.strip())
        if args.walkers and not errors:
            command = [args.walkers, blob, "--spawns", os.path.join(out, m.name + ".spawns.txt"),
                       "--agents", "8", "--frames", "120", "--json"]
            brushes = os.path.join(out, m.name + ".brushes.txt")
            if os.path.exists(brushes):
                command += ["--brushes", brushes]
            run = subprocess.run(command, capture_output=True, text=True)
            if run.returncode != 0:
                errors.append("walkers failed: %s" % run.stderr.strip())
            else:
                result = json.loads(run.stdout)
                if result["fell_out"]:
                    errors.append("%d agents fell out of the level" % result["fell_out"])
                if result["inside_solid"]:
                    errors.append("%d agent-frames inside a solid" % result["inside_solid"])
        print("%-13s %9d %7d  %s" % (m.name, ntri, nspawns, "FAILED" if errors else "ok"))
        for e in errors[:10]:
            print("  " + e)
        failed = failed or bool(errors)
    return 1 if failed else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", help="output folder (required unless --check)")
    ap.add_argument("--small", action="store_true", help="small versions (the --check sizes)")
    ap.add_argument("--level", action="append", help="only this level (repeatable)")
    ap.add_argument("--check", action="store_true",
                    help="generate the small levels and verify them (in --out or a temp folder)")
    ap.add_argument("--bspc", help="with --check: compile each level with this bspc")
    ap.add_argument("--walkers", help="with --check: run a short crowd with this walkers")
    args = ap.parse_args()
    if args.check:
        return run_check(args)
    if not args.out:
        ap.error("--out is required")
    os.makedirs(args.out, exist_ok=True)
    for make in LEVELS:
        name = make.__name__[len("make_"):]
        if args.level and name not in args.level:
            continue
        m = make(args.small)
        write_level(m, args.out)
        print("wrote %s/%s.obj: %d triangles, %d spawns%s" %
              (args.out, m.name, len(m.tris), len(m.spawns),
               ", brushes" if len(m.brushes) == len(m.groups) else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
