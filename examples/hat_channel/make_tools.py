#!/usr/bin/env python3
"""Writes the tools of the hat-channel example as ASCII STL files in
millimetres, in their closed position, as a CAD system exports them:

  die.stl     the female tool, its surface facing up (+z)
  punch.stl   the male tool, the die's surface offset by the stack's
              thickness, facing down (-z), its flange ending at x = +-PUNCH_END
  holder.stl  the blank holder: a flat strip on each flange, from x =
              +-HOLDER_START outwards, at the height of the stack, facing down

The channel runs along y. Its cross-section (x, z), symmetric about x = 0:
a flat bottom at z = -DEPTH, walls at DRAFT degrees from the vertical, a
flange at z = 0; the die's corners are rounded with R_BOTTOM (the valley)
and R_TOP (the crest). The punch is the same section offset by STACK
towards the die's outside, so the two close on a gap of STACK everywhere
(its radii are R_BOTTOM - STACK and R_TOP + STACK).

`python3 make_tools.py --profile` prints instead the die's section and the
length of the curve at a given offset from it (the path of a ply's
mid-surface), used by the example's check.
"""
import math
import sys

DEPTH = 20.0      # mm, channel depth (die)
HALF_BOTTOM = 15.0  # mm, half-width of the bottom to the (sharp) corner
DRAFT = 20.0      # degrees, wall from the vertical
R_BOTTOM = 5.0    # mm, die fillet at the bottom (valley)
R_TOP = 5.0       # mm, die fillet at the top (crest)
HALF_WIDTH = 100.0  # mm, the tools reach x = -100 .. 100
HALF_LENGTH = 60.0  # mm, and y = -60 .. 60
STACK = 1.0       # mm, two plies of 0.5 mm
PUNCH_END = 30.0  # mm, where the punch's flange ends
HOLDER_START = 30.0  # mm, where the holder starts (where the punch ends: no slot between them)
ARC_SEGMENTS = 16  # facets per fillet


def section(offset, end=HALF_WIDTH):
    """The die's section for x >= 0 offset by `offset` (mm) to its outside:
    a list of points (x, z), from x = 0 to x = end on the flange, with arcs
    in ARC_SEGMENTS pieces."""
    a = math.radians(DRAFT)
    c1 = (HALF_BOTTOM, -DEPTH)  # bottom corner (sharp)
    c2 = (HALF_BOTTOM + DEPTH * math.tan(a), 0.0)  # top corner (sharp)
    turn = math.pi / 2 - a  # the profile turns by this at each corner
    # Valley: turns left (counter-clockwise); crest: turns right.
    pts = []

    # Bottom, from x = 0 to the first fillet.
    tb = R_BOTTOM * math.tan(turn / 2)
    tt = R_TOP * math.tan(turn / 2)
    p_start = (0.0, -DEPTH)
    p_b0 = (c1[0] - tb, -DEPTH)
    centre_b = (p_b0[0], -DEPTH + R_BOTTOM)
    p_t1 = (c2[0] + tt, 0.0)
    centre_t = (p_t1[0], -R_TOP)

    pts.append((p_start[0], p_start[1] + offset))
    # Valley fillet: centre above; the point at angle phi from the downward
    # direction, radius R_BOTTOM - offset.
    for k in range(ARC_SEGMENTS + 1):
        phi = turn * k / ARC_SEGMENTS
        d = (math.sin(phi), -math.cos(phi))  # from centre to the die surface
        r = R_BOTTOM - offset
        pts.append((centre_b[0] + r * d[0], centre_b[1] + r * d[1]))
    # Crest fillet: centre below; the outward direction turns back to +z.
    for k in range(ARC_SEGMENTS + 1):
        phi = turn * (1 - k / ARC_SEGMENTS)
        d = (-math.sin(phi), math.cos(phi))
        # at k = 0 the direction is the wall's outside normal (-cos a, sin a)
        r = R_TOP + offset
        pts.append((centre_t[0] + r * d[0], centre_t[1] + r * d[1]))
    pts.append((end, offset))
    return pts


def length(pts):
    return sum(math.dist(p, q) for p, q in zip(pts, pts[1:]))


def whole(pts):
    """The section over the whole width: mirrored to x < 0."""
    return [(-x, z) for x, z in reversed(pts[1:])] + pts


def write_stl(path, name, pts, facing_up, pieces=None):
    """Extrudes the section along y; the triangles face the left of the
    walked profile (+z on a flat piece walked towards +x) when facing_up.
    pieces: the sections' pairs of consecutive points (default: all of
    pts')."""
    y0, y1 = -HALF_LENGTH, HALF_LENGTH
    tris = []
    for (xa, za), (xb, zb) in pieces or list(zip(pts, pts[1:])):
        a0, b0, b1, a1 = (xa, y0, za), (xb, y0, zb), (xb, y1, zb), (xa, y1, za)
        quad = [(a0, b0, b1), (a0, b1, a1)]
        if not facing_up:
            quad = [(t[0], t[2], t[1]) for t in quad]
        tris += quad
    with open(path, "w") as f:
        f.write(f"solid {name}\n")
        for t in tris:
            u = [t[1][i] - t[0][i] for i in range(3)]
            v = [t[2][i] - t[0][i] for i in range(3)]
            n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
            s = math.sqrt(sum(c * c for c in n))
            f.write(f"  facet normal {n[0] / s:.6e} {n[1] / s:.6e} {n[2] / s:.6e}\n    outer loop\n")
            for p in t:
                f.write(f"      vertex {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}\n")
            f.write("    endloop\n  endfacet\n")
        f.write(f"endsolid {name}\n")
    return len(tris)


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--profile":
        off = float(sys.argv[2]) if len(sys.argv) > 2 else 0.0
        pts = section(off)
        for p in pts:
            print(f"{p[0]:.6f} {p[1]:.6f}")
        print(f"# length {length(pts):.6f} mm from x = 0 to x = {pts[-1][0]:.3f} at offset {off} mm")
        return
    import os
    here = os.path.dirname(os.path.abspath(__file__))
    n_die = write_stl(os.path.join(here, "die.stl"), "die", whole(section(0.0)), True)
    n_punch = write_stl(os.path.join(here, "punch.stl"), "punch", whole(section(STACK, PUNCH_END)), False)
    strips = [((-HALF_WIDTH, STACK), (-HOLDER_START, STACK)), ((HOLDER_START, STACK), (HALF_WIDTH, STACK))]
    n_holder = write_stl(os.path.join(here, "holder.stl"), "holder", None, False, strips)
    print(f"die.stl: {n_die} triangles; punch.stl: {n_punch}; holder.stl: {n_holder} (mm)")


if __name__ == "__main__":
    main()
