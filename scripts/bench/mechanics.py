#!/usr/bin/env python3
"""Mechanics benchmark: cost per element per cycle of shell_rf_t3 with the
UD card's laws (ud_hyperelastic + viscoelastic_shear + thermo_linear_bending),
1 and 2 threads. Usage: scripts/bench/mechanics.py [--quick] (after a Release build).
"""
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXE = os.environ.get("THERMOSTAMP_EXE", os.path.join(ROOT, "build", "bin", "thermostamp"))


def job(n, steps):
    size = n * 0.001
    card = json.load(open(os.path.join(ROOT, "share", "materials", "pa66_cf_ud.json")))
    dt_est = 0.8 * 0.7e-3 / (2 * 5.0e6 / (1294.0 * 0.0005)) ** 0.5
    t_end = steps * dt_est
    return {
        "format": "thermostamp-job/1", "name": "bench", "time": {"end": t_end},
        "materials": {"ud": card},
        "parts": [{"name": "ply", "thickness": 0.0005, "material": "ud", "fibre_direction": [1, 1, 0],
                   "mesh": {"generator": "rectangle", "origin": [0, 0, 0], "size": [size, size], "divisions": [n, n]},
                   "initial_temperature": 280.0}],
        "constraints": [
            {"type": "fix", "part": "ply", "box": [[-1e-9, -1, -1], [1e-9, 1, 1]], "dofs": ["x", "y", "z"]},
            {"type": "velocity", "part": "ply", "box": [[size - 1e-9, -1, -1], [size + 1e-9, 1, 1]], "velocity": [1.0, 0, 0]}],
        "solvers": {"mechanics": {"dt_safety": 0.8}, "thermal": None},
        "output": {"interval": t_end, "fields": ["displacement"]},
    }


def run(j, threads):
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "job.json")
        json.dump(j, open(path, "w"))
        out = os.path.join(d, "out")
        subprocess.run([EXE, "run", path, "--out", out, "--threads", str(threads), "--quiet"], check=True)
        return json.load(open(os.path.join(out, "summary.json")))


def main():
    sizes = [71, 224] if "--quick" in sys.argv else [71, 224, 500]
    print("### shell_rf_t3 (membrane + bending) + ud_hyperelastic + viscoelastic_shear + thermo_linear_bending, cost per element per cycle\n")
    print("| elements | threads | cycles | wall time (s) | ns per element-cycle | speed-up |")
    print("|---|---|---|---|---|---|")
    for n in sizes:
        base = None
        for th in (1, 2):
            s = run(job(n, 200), th)
            ne = 2 * n * n
            cyc = s["steps"]["mechanics"]
            ns = s["wall_time_s"] / (ne * cyc) * 1e9
            base = base or s["wall_time_s"]
            print("| %d | %d | %d | %.3f | %.1f | %.2f |" % (ne, th, cyc, s["wall_time_s"], ns, base / s["wall_time_s"]))


if __name__ == "__main__":
    main()
