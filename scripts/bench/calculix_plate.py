#!/usr/bin/env python3
"""Bending in two dimensions against CalculiX: a square plate 100 x 100 x
0.5 mm clamped along x = 0, free elsewhere, a small transverse force at the
corner (L, W) (linear range: deflections of 0.05 % of L). Bending law with
R_1 = R_2 = D = 1 N m and twist_ratio 1 (an isotropic plate with nu = 0:
w = D/2 (k11^2 + k22^2 + 2 k12^2)); CalculiX: S8R shells, E = 12 D / h^3,
nu = 0, linear static, 40 x 40 (converged: 10 x 10 gives the same to 0.02 %).
Prints the deflections at the loaded corner, the free corner, the middle of
the tip edge and the plate's centre for ThermoStamp (shell_rf_t3 on the
rectangle generator's alternating and crossed meshes) and CalculiX.

Usage: scripts/bench/calculix_plate.py [divisions ...]  (default 10 20;
after a Release build; needs ccx, Debian package calculix-ccx).
"""
import os
import subprocess
import sys
import tempfile

from calculix_grid import node_values, quad8_grid, thermostamp_probes

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXE = os.environ.get("THERMOSTAMP_EXE", os.path.join(ROOT, "build", "bin", "thermostamp"))

L = W = 0.1
H = 0.0005
D = 1.0      # bending rigidity (N m)
F = 0.01     # corner force (N)
POINTS = {"loaded corner": (1.0, 1.0), "free corner": (1.0, 0.0), "tip middle": (1.0, 0.5), "centre": (0.5, 0.5)}


def calculix(n, work):
    out, nid = quad8_grid(n, n, L, W, "S8R")
    ids = {k: nid(round(fx * 2 * n), round(fy * 2 * n)) for k, (fx, fy) in POINTS.items()}
    out += ["*NSET, NSET=CLAMP"] + [str(nid(0, j)) for j in range(2 * n + 1)]
    out += ["*NSET, NSET=PROBES"] + [str(v) for v in ids.values()]
    out += ["*MATERIAL, NAME=M", "*ELASTIC", "%.15g, 0" % (12 * D / H ** 3),
            "*SHELL SECTION, ELSET=EALL, MATERIAL=M", "%.15g" % H,
            "*STEP", "*STATIC", "*BOUNDARY", "CLAMP, 1, 6, 0", "*CLOAD", "%d, 3, %.15g" % (ids["loaded corner"], F),
            "*NODE PRINT, NSET=PROBES", "U", "*END STEP"]
    with open(os.path.join(work, "plate.inp"), "w") as f:
        f.write("\n".join(out) + "\n")
    subprocess.run(["ccx", "-i", "plate"], cwd=work, check=True, stdout=subprocess.DEVNULL)
    w = node_values(os.path.join(work, "plate.dat"))
    return {k: w[v][2] for k, v in ids.items()}


def thermostamp(n, pattern, work):
    T = 0.3  # the force ramped over T / 3, mass-proportional damping: at rest at T
    job = {"format": "thermostamp-job/1", "name": "plate", "time": {"end": T},
           "materials": {"m": {"density": 1294.0,
                               "membrane": {"law": "ud_hyperelastic", "k_fibre": 1e5, "p_ct": 1e5, "k_sh": [2.5e4, 0, 0]},
                               "bending": {"law": "thermo_linear_bending", "beta1_T": 0.0, "beta1_B": D,
                                           "beta2_T": 0.0, "beta2_B": D, "twist_ratio": 1.0}}},
           "parts": [{"name": "plate", "mesh": {"generator": "rectangle", "origin": [0, 0, 0], "size": [L, W],
                                                "divisions": [n, n], "pattern": pattern},
                      "thickness": H, "material": "m", "fibre_direction": [1, 0, 0], "initial_temperature": 280.0}],
           "constraints": [
               {"type": "fix", "part": "plate", "box": [[-1e-6, -1, -1], [1e-6, 1, 1]], "dofs": ["x", "y", "z"]},
               {"type": "force", "part": "plate", "box": [[L - 1e-6, W - 1e-6, -1], [L + 1e-6, W + 1e-6, 1]],
                "force": [0, 0, F], "ramp": T / 3}],
           "solvers": {"mechanics": {"dt_safety": 0.8, "damping": 500.0}, "thermal": None},
           "output": {"interval": T, "fields": ["displacement"],
                      "probes": [{"name": k, "part": "plate", "at": [fx * L, fy * W, 0],
                                  "quantities": ["displacement_z"]} for k, (fx, fy) in POINTS.items()]}}
    return {r["probe"]: float(r["value"]) for r in thermostamp_probes(EXE, job, work)}


def main():
    divisions = [int(a) for a in sys.argv[1:]] or [10, 20]
    with tempfile.TemporaryDirectory() as work:
        ref = calculix(40, work)
    print("| mesh | " + " | ".join(POINTS) + " |")
    print("|---|" + "---|" * len(POINTS))
    print("| CalculiX S8R 40 x 40 | " + " | ".join("%.4f mm" % (ref[k] * 1e3) for k in POINTS) + " |")
    for pattern in ("alternating", "crossed"):
        for n in divisions:
            with tempfile.TemporaryDirectory() as work:
                w = thermostamp(n, pattern, work)
            print("| shell_rf_t3 %s %d x %d | " % (pattern, n, n) +
                  " | ".join("%.4f mm (%+.1f %%)" % (w[k] * 1e3, 100 * (w[k] / ref[k] - 1)) for k in POINTS) + " |")


if __name__ == "__main__":
    main()
