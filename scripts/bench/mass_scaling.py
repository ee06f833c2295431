#!/usr/bin/env python3
"""Mass-scaling study of the hemisphere scene (after a Release build).

Runs share/jobs/hemisphere_ud_2ply.json with several mass-scaling target
steps (and optionally damping values), two threads each (--threads), one
run at a time, and prints a Markdown table: added mass, cycles, wall time,
the time from which kinetic / internal energy stays under 5 %, the ratio
at 0.5 / 1 / 1.5 s of the stroke, damping work against internal energy at the end,
shear extrema and the mean temperature under the punch pole at 1 / 2.5 / 5 s.
The answers that matter (temperatures, shear) should not depend on the
mass added; the table shows by how much they do.
Takes about 2 minutes on two cores with the default targets and damping
(about 4 with --damping 20,5).
Usage: scripts/bench/mass_scaling.py [--targets 5e-5,2.5e-5,1.3e-5] [--damping 20] [--threads 2] [--out DIR]
(THERMOSTAMP_EXE selects another build of the executable.)
"""
import argparse
import csv
import json
import os
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXE = os.environ.get("THERMOSTAMP_EXE", os.path.join(ROOT, "build", "bin", "thermostamp"))
JOB = os.path.join(ROOT, "share", "jobs", "hemisphere_ud_2ply.json")


def probe(folder, name, times):
    values = {}
    with open(os.path.join(folder, "probes.csv")) as f:
        for r in csv.DictReader(f):
            if r["probe"] == name and r["quantity"] == "temperature_mean":
                values[float(r["time"])] = float(r["value"])
    return [values[min(values, key=lambda t: abs(t - s))] for s in times]


def ratios(folder, times):
    rows = list(csv.DictReader(open(os.path.join(folder, "energy.csv"))))
    out = []
    for s in times:
        r = min(rows, key=lambda x: abs(float(x["time"]) - s))
        ie = float(r["internal"])
        out.append(float(r["kinetic_half_step"]) / ie if ie > 0 else float("nan"))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--targets", default="5e-5,2.5e-5,1.3e-5")
    ap.add_argument("--damping", default="20")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    base = a.out or tempfile.mkdtemp()
    print("| target step (s) | damping (1/s) | mass added (%) | cycles | wall time (s) | KE/IE < 5 % from (s) "
          "| KE/IE at 0.5 / 1 / 1.5 s | damping / internal work at the end | shear, upper ply (deg) "
          "| shear, lower ply (deg) | mean T at the pole, upper ply, 1 / 2.5 / 5 s | lower ply (degC) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for c in a.damping.split(","):
        for t in a.targets.split(","):
            out = os.path.join(base, "dt%s_c%s" % (t, c))
            subprocess.run([EXE, "run", JOB, "--out", out, "--threads", str(a.threads), "--quiet",
                            "--set", "solvers.mechanics.mass_scaling.target_dt=" + t,
                            "--set", "solvers.mechanics.damping=" + c], check=True)
            s = json.load(open(os.path.join(out, "summary.json")))
            e = s["energy"]
            below = e["kinetic_to_internal"]["under_5_percent_from_s"]
            parts = {p["name"]: p for p in s["parts"]}
            shear = ["%.2f / %+.2f" % (parts[n]["shear_angle_min_deg"], parts[n]["shear_angle_max_deg"])
                     for n in ("ply_top", "ply_bottom")]
            top = probe(out, "pole_top", (1, 2.5, 5))
            bottom = probe(out, "pole_bottom", (1, 2.5, 5))
            print("| %s | %s | %.0f | %d | %.1f | %s | %s | %.2f | %s | %s | %s | %s |" % (
                t, c, max(s["mass_scaling_added_percent"].values()), s["steps"]["mechanics"], s["wall_time_s"],
                "%.2f" % below if below is not None else "never",
                " / ".join("%.3f" % r for r in ratios(out, (0.5, 1.0, 1.5))),
                e["damping"] / e["internal"], shear[0], shear[1],
                " / ".join("%.2f" % v for v in top), " / ".join("%.2f" % v for v in bottom)))


if __name__ == "__main__":
    main()
