"""What the CalculiX cross-check scripts share: a rectangle of 8-node
quadrilaterals (CPS8 or S8R) as CalculiX input lines, the node values of
a *NODE PRINT block of the .dat file, and a ThermoStamp run of a job with
its probe samples."""
import csv
import json
import os
import re
import subprocess


def quad8_grid(nx, ny, lx, ly, element):
    """Input lines (*NODE and *ELEMENT) of nx x ny 8-node quadrilaterals on
    [0, lx] x [0, ly], and nid(i, j), the node at (lx i / 2 nx, ly j / 2 ny)."""
    gx = 2 * nx + 1
    nid = lambda i, j: j * gx + i + 1
    out = ["*NODE"]
    for j in range(2 * ny + 1):
        for i in range(2 * nx + 1):
            if i % 2 == 0 or j % 2 == 0:
                out.append("%d, %.15g, %.15g, 0" % (nid(i, j), lx * i / (2 * nx), ly * j / (2 * ny)))
    out.append("*ELEMENT, TYPE=%s, ELSET=EALL" % element)
    e = 1
    for j in range(ny):
        for i in range(nx):
            I, J = 2 * i, 2 * j
            c = [nid(I, J), nid(I + 2, J), nid(I + 2, J + 2), nid(I, J + 2),
                 nid(I + 1, J), nid(I + 2, J + 1), nid(I + 1, J + 2), nid(I, J + 1)]
            out.append("%d, %s" % (e, ", ".join(map(str, c))))
            e += 1
    return out, nid


def node_values(dat_path):
    """{node: (v1, v2, v3)} from the lines 'node v1 v2 v3' of a .dat file."""
    values = {}
    with open(dat_path) as f:
        for line in f:
            m = re.match(r"^\s+(\d+)\s+(\S+)\s+(\S+)\s+(\S+)\s*$", line)
            if m:
                values[int(m.group(1))] = (float(m.group(2)), float(m.group(3)), float(m.group(4)))
    return values


def thermostamp_probes(exe, job, work):
    """Runs the job (a dict) with the executable exe in the folder work and
    returns the rows of its probes.csv (dicts: probe, quantity, time, value)."""
    path = os.path.join(work, job["name"] + ".json")
    with open(path, "w") as f:
        json.dump(job, f)
    out = os.path.join(work, "out")
    subprocess.run([exe, "run", path, "--out", out, "--quiet"], check=True)
    with open(os.path.join(out, "probes.csv")) as f:
        return list(csv.DictReader(f))
