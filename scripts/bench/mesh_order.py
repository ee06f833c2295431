#!/usr/bin/env python3
"""Mesh files in their own order against the order of `mesh.reorder`: cost per
element per cycle of the mechanics benchmark's plate (scripts/bench/mechanics.py:
shell_rf_t3 with the UD card's laws, bending every step, pulled and lifted at
an edge, one thread) when its mesh comes from a file.

The plates (1 mm triangles, 224 x 224 mm, about 100 000 triangles; --size for
another side in mm):
- rows: the rectangle generator's mesh written to a file as it is (its
  triangles row by row, the order the generator's benchmarks run in);
- shuffled: the same triangles in a random order (seed 1), the worst case;
- gmsh: the square meshed by Gmsh's Frontal-Delaunay algorithm at the same
  element size, in the order Gmsh writes (needs `gmsh` on the PATH; left out
  without it).
Each runs with `"reorder": false` (the file's order) and true (the default),
--reps times in turn; the smallest element time of each is kept. The log's
line on the mesh gives how far apart neighbouring triangles are.

Usage: scripts/bench/mesh_order.py [--reps N] [--size MM] (after a Release build)
"""
import argparse
import json
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mechanics  # noqa: E402


def rectangle(n, h):
    """Nodes and triangles of the rectangle generator's alternating pattern."""
    nodes = [(i * h, j * h) for j in range(n + 1) for i in range(n + 1)]
    tri = []
    for j in range(n):
        for i in range(n):
            a, b, c, d = j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1, (j + 1) * (n + 1) + i
            tri += [(a, b, c), (a, c, d)] if (i + j) % 2 == 0 else [(a, b, d), (b, c, d)]
    return nodes, tri


def write_msh(path, nodes, tri):
    with open(path, "w") as f:
        f.write("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n%d\n" % len(nodes))
        for k, (x, y) in enumerate(nodes):
            f.write("%d %.17g %.17g 0\n" % (k + 1, x, y))
        f.write("$EndNodes\n$Elements\n%d\n" % len(tri))
        for e, t in enumerate(tri):
            f.write("%d 2 2 1 1 %d %d %d\n" % (e + 1, t[0] + 1, t[1] + 1, t[2] + 1))
        f.write("$EndElements\n")


def gmsh_plate(path, size, h):
    geo = path + ".geo"
    with open(geo, "w") as f:
        f.write("L = %.17g; lc = %.17g;\n" % (size, h))
        f.write("Point(1) = {0,0,0,lc}; Point(2) = {L,0,0,lc}; Point(3) = {L,L,0,lc}; Point(4) = {0,L,0,lc};\n"
                "Line(1) = {1,2}; Line(2) = {2,3}; Line(3) = {3,4}; Line(4) = {4,1};\n"
                "Curve Loop(1) = {1,2,3,4}; Plane Surface(1) = {1}; Physical Surface(\"ply\") = {1};\n")
    subprocess.run(["gmsh", "-2", "-algo", "front2d", "-format", "msh22", geo, "-o", path], check=True,
                   capture_output=True)


def triangles_in(path):
    lines = open(path).read().split("\n")
    k = lines.index("$Elements")
    return sum(1 for line in lines[k + 2:k + 2 + int(lines[k + 1])] if line.split()[1] == "2")


def run(job, reorder):
    with tempfile.TemporaryDirectory() as d:
        j = json.loads(json.dumps(job))
        j["parts"][0]["mesh"]["reorder"] = reorder
        path = os.path.join(d, "job.json")
        json.dump(j, open(path, "w"))
        out = os.path.join(d, "out")
        r = subprocess.run([mechanics.EXE, "run", path, "--out", out, "--threads", "1"], capture_output=True,
                           text=True)
        if r.returncode != 0:
            sys.exit("mesh_order.py: thermostamp run failed (exit %d):\n%s" % (r.returncode, r.stderr))
        apart = re.search(r"neighbouring triangles at most (\d+) places apart", r.stderr + r.stdout)
        return json.load(open(os.path.join(out, "summary.json"))), int(apart.group(1)) if apart else None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--reps", type=int, default=3, help="runs per case; the smallest element time is kept")
    ap.add_argument("--size", type=int, default=224, help="side of the plate in mm (1 mm triangles)")
    args = ap.parse_args()
    n, h = args.size, 0.001
    with tempfile.TemporaryDirectory() as d:
        nodes, tri = rectangle(n, h)
        meshes = {}
        meshes["rows"] = os.path.join(d, "rows.msh")
        write_msh(meshes["rows"], nodes, tri)
        shuffled = list(tri)
        random.Random(1).shuffle(shuffled)
        meshes["shuffled"] = os.path.join(d, "shuffled.msh")
        write_msh(meshes["shuffled"], nodes, shuffled)
        if shutil.which("gmsh"):
            meshes["gmsh"] = os.path.join(d, "gmsh.msh")
            gmsh_plate(meshes["gmsh"], n * h, 1.2 * h)  # about as many triangles as the plate's 2 n^2
        else:
            print("(gmsh not found: the Gmsh plate is left out)\n")
        print("### Mesh files: the file's order against `mesh.reorder` (one thread, smallest of %d runs, "
              "bending every step)\n" % args.reps)
        print("| mesh | triangles | order | neighbours at most apart | cycles | ns per element-cycle (elements) "
              "| ratio to the reordered | energies of both orders (relative difference) |")
        print("|---|---|---|---|---|---|---|---|")
        for name, path in meshes.items():
            job = mechanics.job(n, 200)
            job["parts"][0]["mesh"] = {"file": path}
            ne = triangles_in(path)
            best, apart, energy = {}, {}, {}
            for _ in range(args.reps):
                for reorder in (False, True):
                    s, a = run(job, reorder)
                    t = s["timing_s"]["elements_and_laws"] / (ne * s["steps"]["mechanics"]) * 1e9
                    if reorder not in best or t < best[reorder][0]:
                        best[reorder] = (t, s["steps"]["mechanics"])
                    apart[reorder] = a
                    energy[reorder] = s["energy"]["internal"]
            diff = abs(energy[False] - energy[True]) / abs(energy[True])
            for reorder in (False, True):
                t, cycles = best[reorder]
                print("| %s | %d | %s | %s | %d | %.1f | %.2f | %s |" % (
                    name, ne, "reorder" if reorder else "file", apart[reorder], cycles, t, t / best[True][0],
                    "%.1e" % diff if reorder else ""))


if __name__ == "__main__":
    main()
