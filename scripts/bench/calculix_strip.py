#!/usr/bin/env python3
"""The clamped off-axis UD strip of CalculiX.ClampedOffAxisUdStrip, as a
figure: displacements along the strip's axis and its lateral edges, from
ThermoStamp (shell_rf_t3, 80 x 16 cells) and CalculiX (CPS8, 160 x 32), for
fibres at 30 and 60 degrees. Writes docs/figures/calculix_strip.png.

Usage: scripts/bench/calculix_strip.py (after a Release build; needs ccx,
Debian package calculix-ccx, and matplotlib).
"""
import math
import os
import subprocess
import tempfile

from calculix_grid import node_values, quad8_grid, thermostamp_probes
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXE = os.environ.get("THERMOSTAMP_EXE", os.path.join(ROOT, "build", "bin", "thermostamp"))
FIG = os.path.join(ROOT, "docs", "figures")

L, W, H = 0.1, 0.02, 0.0005          # strip (m)
KF, PCT, KSH = 5.0e4, 5.0e3, 2.0e3    # UD law (N/m)
U = 5.0e-5                            # end displacement (m)
LINES = (0.0, 0.5, 1.0)               # y / W of the plotted lines


def calculix(deg, nx, ny, work):
    """CPS8 plane stress, E1 = 2 k_fibre / h, E2 = 2 p_ct / h, G12 = 2 k_sh / h."""
    a = math.radians(deg)
    out, nid = quad8_grid(nx, ny, L, W, "CPS8")
    out += ["*NSET, NSET=LEFT"] + [str(nid(0, j)) for j in range(2 * ny + 1)]
    out += ["*NSET, NSET=RIGHT"] + [str(nid(2 * nx, j)) for j in range(2 * ny + 1)]
    lines = {}
    for f in LINES:
        j = round(f * 2 * ny)
        lines[f] = [(L * i / (2 * nx), nid(i, j)) for i in range(2 * nx + 1)]
    out += ["*NSET, NSET=PLOT"] + sorted({str(n) for v in lines.values() for _, n in v})
    E1, E2, G12 = 2 * KF / H, 2 * PCT / H, 2 * KSH / H
    out += ["*MATERIAL, NAME=UD", "*ELASTIC, TYPE=ENGINEERING CONSTANTS",
            "%.15g, %.15g, %.15g, 0, 0, 0, %.15g, %.15g" % (E1, E2, E2, G12, G12), "%.15g" % G12,
            "*ORIENTATION, NAME=OR1, SYSTEM=RECTANGULAR",
            "%.15g, %.15g, 0, %.15g, %.15g, 0" % (math.cos(a), math.sin(a), -math.sin(a), math.cos(a)),
            "*SOLID SECTION, ELSET=EALL, MATERIAL=UD, ORIENTATION=OR1", "%.15g" % H,
            "*STEP", "*STATIC", "*BOUNDARY", "LEFT, 1, 2, 0", "RIGHT, 2, 2, 0", "RIGHT, 1, 1, %.15g" % U,
            "*NODE PRINT, NSET=PLOT", "U", "*END STEP"]
    with open(os.path.join(work, "strip.inp"), "w") as f:
        f.write("\n".join(out) + "\n")
    subprocess.run(["ccx", "-i", "strip"], cwd=work, check=True, stdout=subprocess.DEVNULL)
    disp = node_values(os.path.join(work, "strip.dat"))
    return {f: [(x, disp[n][:2]) for x, n in v] for f, v in lines.items()}


def thermostamp(deg, nx, ny, work):
    a = math.radians(deg)
    t_end = 0.1
    probes = []
    for f in LINES:
        for i in range(nx + 1):
            probes.append({"name": "y%g_%d" % (f, i), "part": "strip", "at": [L * i / nx, f * W, 0.0],
                           "quantities": ["displacement_x", "displacement_y"]})
    job = {"format": "thermostamp-job/1", "name": "clamped_strip", "time": {"end": t_end},
           "materials": {"ud": {"density": 1294.0, "membrane": {"law": "ud_hyperelastic", "k_fibre": KF,
                                                                "p_ct": PCT, "k_sh": [KSH, 0, 0]}}},
           "parts": [{"name": "strip", "mesh": {"generator": "rectangle", "origin": [0, 0, 0], "size": [L, W],
                                                "divisions": [nx, ny]},
                      "thickness": H, "material": "ud", "fibre_direction": [math.cos(a), math.sin(a), 0],
                      "initial_temperature": 280.0}],
           "constraints": [
               {"type": "fix", "part": "strip", "box": [[-1e-6, -1, -1], [1e-6, 1, 1]], "dofs": ["x", "y", "z"]},
               {"type": "velocity", "part": "strip", "box": [[L - 1e-6, -1, -1], [L + 1e-6, 1, 1]],
                "velocity": [U / t_end, 0, 0]},
               {"type": "fix", "part": "*", "box": [[-1, -1, -1], [1, 1, 1]], "dofs": ["z"]}],
           "solvers": {"mechanics": {"dt_safety": 0.8, "damping": 200.0}, "thermal": None},
           "output": {"interval": t_end, "fields": ["displacement"], "probes": probes}}
    vals = {(r["probe"], r["quantity"]): float(r["value"])
            for r in thermostamp_probes(EXE, job, work) if abs(float(r["time"]) - t_end) < 1e-9}
    return {f: [(L * i / nx, (vals[("y%g_%d" % (f, i), "displacement_x")], vals[("y%g_%d" % (f, i), "displacement_y")]))
                for i in range(nx + 1)] for f in LINES}


def main():
    os.makedirs(FIG, exist_ok=True)
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5), sharex=True)
    colours = {0.0: "tab:blue", 0.5: "tab:green", 1.0: "tab:red"}
    for col, deg in enumerate((30, 60)):
        with tempfile.TemporaryDirectory() as w1, tempfile.TemporaryDirectory() as w2:
            ref = calculix(deg, 160, 32, w1)
            ts = thermostamp(deg, 80, 16, w2)
        worst = 0.0
        for row, comp in enumerate(("u_x", "u_y")):
            ax = axes[row][col]
            for f in LINES:
                ax.plot([x * 1e3 for x, _ in ref[f]], [u[row] * 1e6 for _, u in ref[f]], "-", color=colours[f],
                        lw=1.2, label="CalculiX CPS8 160 x 32, y = %g W" % f)
                ax.plot([x * 1e3 for x, _ in ts[f]], [u[row] * 1e6 for _, u in ts[f]], "o", color=colours[f],
                        ms=3, mfc="none", label="ThermoStamp shell_rf_t3 80 x 16, y = %g W" % f)
                r = dict((round(x, 9), u) for x, u in ref[f])
                for x, u in ts[f]:
                    worst = max(worst, abs(u[row] - r[round(x, 9)][row]) / U)
            ax.set_ylabel("%s (um)" % comp)
            ax.grid(alpha=0.3)
            if row == 0:
                ax.set_title("fibres at %d degrees" % deg)
            if row == 1:
                ax.set_xlabel("x (mm)")
        print("%d deg: largest difference along the lines %.3f %% of the end displacement" % (deg, 100 * worst))
    axes[0][0].legend(fontsize=7)
    fig.suptitle("UD strip 100 x 20 mm, both ends clamped, one pulled 0.05 mm: displacements along three lines")
    fig.tight_layout()
    path = os.path.join(FIG, "calculix_strip.png")
    fig.savefig(path, dpi=110)
    print("wrote", path)


if __name__ == "__main__":
    main()
