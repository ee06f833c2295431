#!/usr/bin/env python3
"""Meshed tools: the hemisphere scene with its three revolved tools written
out as STL files, against the same scene with the analytic tools.

Each tool's profile is turned into triangles over the quarter the scene
models (plus a few degrees either side), in one of two ways:

  uniform  every piece cut into segments of at most --size (m), and as
           many sectors around the axis as make the widest ring's arcs
           that long;
  cad      as CAD exporters tessellate: a straight piece is one segment
           (a flat ring of the die becomes long thin triangles from its
           inner to its outer edge), an arc as many as a chord tolerance
           --chord (m) asks, the sectors around the axis by the same
           tolerance at the tool's widest radius.

and the triangles are written in rows (ring after ring) or, in the
variants ending in -shuffled, in a random order (seeded). Prints, per
variant, the number of triangles, the contact time and wall time of the
run, and the pole's displacement at the end, the largest punch force and
the largest shear angle, to set beside those of the analytic tools.

Usage: scripts/bench/tool_mesh.py [--end 0.5] [--size 0.002] [--chord 5e-5]
                                  [--threads 1] [--variants a,b,...] [--keep DIR]
(after a Release build). Variants: revolved, uniform, uniform-shuffled,
cad, cad-shuffled.
"""
import argparse
import csv
import json
import math
import os
import random
import struct
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXE = os.environ.get("THERMOSTAMP_EXE", os.path.join(ROOT, "build", "bin", "thermostamp"))
SCENE = os.path.join(ROOT, "share", "jobs", "hemisphere_ud_2ply.json")
MARGIN = math.radians(3.0)


def piece_points(piece, size, chord, mode):
    """(r, z) points along one profile piece, both ends included."""
    if "line" in piece:
        (r0, z0), (r1, z1) = piece["line"]
        n = 1 if mode == "cad" else max(1, math.ceil(math.hypot(r1 - r0, z1 - z0) / size))
        return [(r0 + (r1 - r0) * k / n, z0 + (z1 - z0) * k / n) for k in range(n + 1)]
    a = piece["arc"]
    (r0, z0), (r1, z1), (rc, zc) = a["from"], a["to"], a["centre"]
    rad = math.hypot(r0 - rc, z0 - zc)
    t0 = math.atan2(z0 - zc, r0 - rc)
    t1 = math.atan2(z1 - zc, r1 - rc)
    cross = (r0 - rc) * (z1 - zc) - (z0 - zc) * (r1 - rc)
    sweep = t1 - t0
    if cross > 0 and sweep < 0:
        sweep += 2 * math.pi
    if cross < 0 and sweep > 0:
        sweep -= 2 * math.pi
    step = size / rad if mode == "uniform" else 2 * math.acos(max(-1.0, 1 - chord / rad))
    n = max(1, math.ceil(abs(sweep) / step))
    pts = [(rc + rad * math.cos(t0 + sweep * k / n), zc + rad * math.sin(t0 + sweep * k / n)) for k in range(n + 1)]
    pts[0], pts[-1] = (r0, z0), (r1, z1)
    return pts


def tessellate(tool, size, chord, mode):
    """Triangles (three xyz points each, outward normals by the right-hand rule)."""
    surf = tool["surface"]
    origin = surf.get("axis", {}).get("origin", [0, 0, 0])
    prof = []  # (r, z, outward normal of the piece: left of the direction of travel)
    for piece in surf["profile"]:
        pts = piece_points(piece, size, chord, mode)
        for k in range(len(pts) - 1):
            (ra, za), (rb, zb) = pts[k], pts[k + 1]
            prof.append(((ra, za), (rb, zb), (-(zb - za), rb - ra)))
    rmax = max(max(p[0][0], p[1][0]) for p in prof)
    span = math.pi / 2 + 2 * MARGIN
    step = size / rmax if mode == "uniform" else 2 * math.acos(1 - chord / rmax)
    ns = max(1, math.ceil(span / step))
    th = [-MARGIN + span * k / ns for k in range(ns + 1)]
    xyz = lambda r, z, t: (origin[0] + r * math.cos(t), origin[1] + r * math.sin(t), origin[2] + z)
    tris = []
    for (ra, za), (rb, zb), (nr, nz) in prof:
        for k in range(ns):
            t0, t1 = th[k], th[k + 1]
            quad = [xyz(ra, za, t0), xyz(rb, zb, t0), xyz(rb, zb, t1), xyz(ra, za, t1)]
            tm = 0.5 * (t0 + t1)
            want = (nr * math.cos(tm), nr * math.sin(tm), nz)
            for tri in ((quad[0], quad[1], quad[2]), (quad[0], quad[2], quad[3])):
                u = [tri[1][d] - tri[0][d] for d in range(3)]
                v = [tri[2][d] - tri[0][d] for d in range(3)]
                n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
                if math.sqrt(sum(c * c for c in n)) < 1e-14:  # a corner on the axis
                    continue
                if sum(n[d] * want[d] for d in range(3)) < 0:
                    tri = (tri[0], tri[2], tri[1])
                tris.append(tri)
    return tris


def write_stl(path, tris):
    with open(path, "wb") as f:
        f.write(b"ThermoStamp benchmark tool".ljust(80, b" "))
        f.write(struct.pack("<I", len(tris)))
        for tri in tris:
            f.write(struct.pack("<3f", 0, 0, 0))
            for p in tri:
                f.write(struct.pack("<3f", *p))
            f.write(b"\0\0")


def run(job, threads, out):
    path = os.path.join(out + ".json")
    json.dump(job, open(path, "w"))
    subprocess.run([EXE, "run", path, "--out", out, "--threads", str(threads), "--quiet"], check=True)
    s = json.load(open(os.path.join(out, "summary.json")))
    rows = list(csv.DictReader(open(os.path.join(out, "probes.csv"))))
    pole = [float(r["value"]) for r in rows if r["probe"] == "pole_top" and r["quantity"] == "displacement_z"]
    punch = [t for t in s["tools"] if t["name"] == "punch"][0]
    shear = max(p["shear_angle_max_deg"] for p in s["parts"])
    return s, pole[-1], punch["force_max_N"], shear


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--end", type=float, default=0.5)
    ap.add_argument("--size", type=float, default=0.002)
    ap.add_argument("--chord", type=float, default=5e-5)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--variants", default="revolved,uniform,uniform-shuffled,cad,cad-shuffled")
    ap.add_argument("--keep", help="write the jobs, STL files and results to this folder and keep them")
    a = ap.parse_args()
    base = json.load(open(SCENE))
    base["time"]["end"] = a.end
    base["output"]["interval"] = a.end
    print("Hemisphere scene to t = %g s, %d thread(s); uniform size %g m, chord tolerance %g m\n" % (
        a.end, a.threads, a.size, a.chord))
    print("| tools | triangles (punch / die / holder) | contact (s) | wall (s) | pole u_z (mm) | punch force, largest (N) | shear angle, largest (deg) |")
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        d = a.keep or tmp
        os.makedirs(d, exist_ok=True)
        for variant in a.variants.split(","):
            job = json.loads(json.dumps(base))
            counts = []
            if variant != "revolved":
                mode, _, shuffled = variant.partition("-")
                for tool in job["tools"]:
                    tris = tessellate(tool, a.size, a.chord, mode)
                    if shuffled:
                        random.Random(7).shuffle(tris)
                    path = os.path.join(d, "%s-%s.stl" % (variant, tool["name"]))
                    write_stl(path, tris)
                    tool["surface"] = {"type": "mesh", "file": path}
                    counts.append(len(tris))
            s, pole, punch, shear = run(job, a.threads, os.path.join(d, variant))
            print("| %s | %s | %.2f | %.2f | %.4f | %.1f | %.2f |" % (
                variant, " / ".join(str(c) for c in counts) or "analytic", s["timing_s"]["contact"], s["wall_time_s"],
                1e3 * pole, punch, shear))


if __name__ == "__main__":
    main()
