#!/usr/bin/env python3
"""Mesh refinement of the hemisphere scene (after a Release build).

Runs share/jobs/hemisphere_ud_2ply.json (fibres [1,-1,0]) and
hemisphere_ud_2ply_fibres_y.json, each on its own mesh pattern, on 10, 15,
20 and 30 cells per ply edge, one thread each, two runs at a time, and
prints a Markdown table: cycles, wall time, ns per element-cycle, shear
extrema per ply, energy balance and the lower ply's mean temperature under
the punch pole at t = 1..5 s. Mass scaling to --target-dt (default 5e-5 s,
the step of the tables in docs/benchmarks.md; the jobs' own 1.4e-5 s
takes 3.3 times longer).
Takes about 15 minutes on two cores.
Usage: scripts/bench/refinement.py [--cells 10,20,30] [--target-dt 5e-5] [--out DIR]
                                   [--pattern crossed|alternating] [--fibres diagonal|y|both]
(THERMOSTAMP_EXE selects another build of the executable.)
"""
import argparse
import csv
import json
import os
import subprocess
import tempfile
from concurrent.futures import ThreadPoolExecutor

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXE = os.environ.get("THERMOSTAMP_EXE", os.path.join(ROOT, "build", "bin", "thermostamp"))
JOBS = {"[1,-1,0]": "hemisphere_ud_2ply.json", "along y": "hemisphere_ud_2ply_fibres_y.json"}


def run(job, cells, out, target_dt, pattern):
    extra = ["--set", "parts.*.mesh.pattern=" + pattern] if pattern else []
    subprocess.run([EXE, "run", os.path.join(ROOT, "share", "jobs", job), "--out", out, "--threads", "1", "--quiet",
                    "--set", "parts.*.mesh.divisions=[%d,%d]" % (cells, cells),
                    "--set", "solvers.mechanics.mass_scaling.target_dt=" + target_dt] + extra, check=True)
    return out


def pole_history(folder):
    values = {}
    with open(os.path.join(folder, "probes.csv")) as f:
        for r in csv.DictReader(f):
            if r["probe"] == "pole_bottom" and r["quantity"] == "temperature_mean":
                values[float(r["time"])] = float(r["value"])
    return [values[min(values, key=lambda t: abs(t - s))] for s in (1, 2, 3, 4, 5)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cells", default="10,15,20,30")
    ap.add_argument("--target-dt", default="5e-5")
    ap.add_argument("--out", default=None)
    ap.add_argument("--pattern", default=None, help="mesh pattern of both jobs (default: each job's own)")
    ap.add_argument("--fibres", default="both", choices=["diagonal", "y", "both"])
    a = ap.parse_args()
    jobs = {k: v for k, v in JOBS.items() if a.fibres == "both" or (a.fibres == "y") == (k == "along y")}
    cells = [int(c) for c in a.cells.split(",")]
    base = a.out or tempfile.mkdtemp()
    tasks = [(label, job, n, os.path.join(base, "%s_%d" % (job.replace(".json", ""), n)))
             for label, job in jobs.items() for n in cells]
    with ThreadPoolExecutor(max_workers=2) as pool:
        list(pool.map(lambda t: run(t[1], t[2], t[3], a.target_dt, a.pattern), tasks))
    print("| fibres | cells per ply, mesh pattern | elements | cycles | wall time (s) | ns per element-cycle | shear, upper ply (deg) "
          "| shear, lower ply (deg) | energy balance | lower ply at the pole, mean T at 1 / 2 / 3 / 4 / 5 s (degC) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for label, job, n, out in tasks:
        s = json.load(open(os.path.join(out, "summary.json")))
        elements = sum(p["elements"] for p in s["parts"])
        cyc = s["steps"]["mechanics"]
        shear = ["%.2f / %+.2f" % (p["shear_angle_min_deg"], p["shear_angle_max_deg"]) for p in s["parts"]]
        # parts are listed lower ply first in both jobs
        pattern = a.pattern or json.load(open(os.path.join(ROOT, "share", "jobs", job)))["parts"][0]["mesh"].get(
            "pattern", "alternating")
        print("| %s | %d x %d, %s | %d | %d | %.1f | %.0f | %s | %s | %.1e | %s |" % (
            label, n, n, pattern, elements, cyc, s["wall_time_s"], s["wall_time_s"] / (elements * cyc) * 1e9, shear[1],
            shear[0], s["energy"]["balance_error"], " / ".join("%.2f" % v for v in pole_history(out))))


if __name__ == "__main__":
    main()
