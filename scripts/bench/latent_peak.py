#!/usr/bin/env python3
"""Accuracy of a specific heat table against the step: a lumped ply
(shell2d, Robin h 1000 + 500 W/(m2 K) to 200 degC, from 300 degC) cooled
through a latent heat peak of 30 kJ/kg, 20 K or 5 K wide, against the
closed form of rho h c(T) dT/dt = -H (T - T_a); with a constant specific
heat for comparison. Prints the largest error over 4 s (samples every
0.1 s) for each step.

Usage: scripts/bench/latent_peak.py   (after a build in build/)
"""
import csv
import json
import math
import os
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXE = os.environ.get("THERMOSTAMP_EXE", os.path.join(ROOT, "build", "bin", "thermostamp"))
TA, T0, RHO, H, HSUM = 200.0, 300.0, 1294.0, 0.0005, 1500.0


def job(rows, dt):
    return {
        "format": "thermostamp-job/1", "name": "latent_peak", "time": {"end": 4.0},
        "materials": {"ply": {"density": RHO, "specific_heat": rows, "conductivity": [3.89, 0.31, 0.31]}},
        "parts": [{"name": "ply", "mesh": {"generator": "rectangle", "origin": [0, 0, 0], "size": [0.01, 0.01],
                                           "divisions": [2, 2]},
                   "thickness": H, "material": "ply", "initial_temperature": T0, "thickness_layers": 4}],
        "interactions": [{"type": "heat_exchange", "part": "ply", "face": "top", "h": 1000.0, "ambient": TA},
                         {"type": "heat_exchange", "part": "ply", "face": "bottom", "h": 500.0, "ambient": TA}],
        "solvers": {"mechanics": None, "thermal": {"splitter": "shell2d", "through_thickness": "implicit", "dt": dt}},
        "output": {"interval": 0.1, "fields": ["temperature_mean"], "checkpoint_at_end": False,
                   "probes": [{"name": "c", "part": "ply", "at": [0.005, 0.005, 0],
                               "quantities": ["temperature_profile"], "interval": 0.1}]},
    }


def c_of(rows, T):
    if T <= rows[0][0]:
        return rows[0][1]
    if T >= rows[-1][0]:
        return rows[-1][1]
    for (a, ca), (b, cb) in zip(rows, rows[1:]):
        if a <= T <= b:
            return ca + (cb - ca) * (T - a) / (b - a)


def time_to(rows, T):
    """t(T) = (rho h / H) int_T^T0 c(s) / (s - T_a) ds, c linear on each piece."""
    pts = [T] + [r[0] for r in rows if T < r[0] < T0] + [T0]
    s = 0.0
    for s1, s2 in zip(pts, pts[1:]):
        if s2 <= s1:
            continue
        slope = (c_of(rows, s2) - c_of(rows, s1)) / (s2 - s1)
        ca = c_of(rows, s1) + slope * (TA - s1)
        s += ca * math.log((s2 - TA) / (s1 - TA)) + slope * (s2 - s1)
    return RHO * H / HSUM * s


def exact(rows, t):
    lo, hi = TA + 1e-9, T0
    for _ in range(200):
        m = 0.5 * (lo + hi)
        if time_to(rows, m) > t:
            lo = m
        else:
            hi = m
    return 0.5 * (lo + hi)


def main():
    cases = [("constant 1775", 1775.0, [[0.0, 1775.0]]),
             ("peak 20 K wide (c up to 4775)", [[220.0, 1775.0], [230.0, 4775.0], [240.0, 1775.0]], None),
             ("peak 5 K wide (c up to 13775)", [[227.5, 1775.0], [230.0, 13775.0], [232.5, 1775.0]], None)]
    print("| specific heat | dt (s) | largest error (K) |")
    print("|---|---|---|")
    with tempfile.TemporaryDirectory() as d:
        for name, value, exact_rows in cases:
            for dt in (0.01, 0.005, 0.0025, 0.00125):
                path = os.path.join(d, "job.json")
                json.dump(job(value, dt), open(path, "w"))
                out = os.path.join(d, "out")
                subprocess.run([EXE, "run", path, "--out", out, "--quiet"], check=True)
                rows = exact_rows or value
                err = 0.0
                for r in csv.DictReader(open(os.path.join(out, "probes.csv"))):
                    err = max(err, abs(float(r["value"]) - exact(rows, float(r["time"]))))
                print("| %s | %g | %.4f |" % (name, dt, err))


if __name__ == "__main__":
    main()
