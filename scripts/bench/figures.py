#!/usr/bin/env python3
"""Regenerates the figures of docs/verification.md (after a Release build).

Runs share/verification/slab_robin_study.json, patch_study.json,
hemisphere_study.json (about 2.5 minutes on two cores), the demo job and
the default hemisphere job with a conductance that follows the contact
pressure (half a minute), and writes PNG files into docs/figures/.
With --crystallisation, only the crystallisation studies' figures
(about 6 minutes); with --blank, only the cut patterns of the hemisphere
cup cut at r = 80 mm, UD with either fibre layout and woven, and the top
plies' patterns on a roll 600 mm wide (two minutes); with --conductivity, only the slab cooled with a conductivity
that follows the temperature against its reference (seconds); with
--grippers, only the bias-extension specimen pulled by its clamp and by
grippers with rigid, swivelling and flexible jaws, and plates turned by
swivelling jaws against rigid-body dynamics (seconds).
"""
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXE = os.environ.get("THERMOSTAMP_EXE", os.path.join(ROOT, "build", "bin", "thermostamp"))
FIG = os.path.join(ROOT, "docs", "figures")


def profiles(folder, probe):
    out = {}
    with open(os.path.join(folder, "probes.csv")) as f:
        for r in csv.DictReader(f):
            if r["probe"] == probe and r["quantity"] == "temperature_profile":
                out.setdefault(float(r["time"]), []).append((float(r["z"]), float(r["value"])))
    return out


def closest(d, t):
    return d[min(d, key=lambda k: abs(k - t))]


def hemisphere_conductance(tmp):
    """The default hemisphere job with the conductance table of the user
    guide on its four pairs: the conductance of each face at the end."""
    with open(os.path.join(ROOT, "share", "jobs", "hemisphere_ud_2ply.json")) as f:
        job = json.load(f)
    for c in job["interactions"]:
        if c.get("type") == "contact":
            c.pop("conductance", None)
            c["conductance_pressures"] = [0.0, 1e5, 1e6]
            c["conductance_values"] = [300.0, 1000.0, 2000.0]
    job["output"]["fields"].append("conductance")
    path = os.path.join(tmp, "hemisphere_conductance.json")
    with open(path, "w") as f:
        json.dump(job, f, indent=1)
    out = os.path.join(tmp, "hemisphere_conductance")
    subprocess.run([EXE, "run", path, "--out", out, "--quiet", "--threads", "2"], check=True)
    subprocess.run([EXE, "report", out], check=True, stdout=subprocess.DEVNULL)
    for ply in ("ply_top", "ply_bottom"):
        shutil.copy(os.path.join(out, "figures", "conductance_%s.png" % ply),
                    os.path.join(FIG, "hemi_conductance_table_%s.png" % ply))


def crystallisation(tmp):
    """The crystallisation studies of the user guide and docs/verification.md
    (share/studies/hemisphere_crystallisation.json and
    hemisphere_crystallisation_strategies.json, about 6 minutes on two
    cores): the latent heat against the reference, the run with kinetics,
    and the thermal strategies with kinetics."""
    studies = os.path.join(ROOT, "share", "studies")
    runs = {}
    for study in ("hemisphere_crystallisation", "hemisphere_crystallisation_strategies"):
        runs[study] = os.path.join(tmp, study)
        subprocess.run([EXE, "study", os.path.join(studies, study + ".json"), "--out", runs[study], "--quiet",
                        "--threads", "2"], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    latent = runs["hemisphere_crystallisation"]
    subprocess.run([EXE, "report", os.path.join(latent, "latent-heat-230"), "--against",
                    os.path.join(latent, "reference")], check=True, stdout=subprocess.DEVNULL)
    shutil.copy(os.path.join(latent, "latent-heat-230", "figures", "against", "plies.png"),
                os.path.join(FIG, "hemi_crystallisation_plies.png"))
    kinetics = os.path.join(latent, "kinetics")
    subprocess.run([EXE, "report", kinetics], check=True, stdout=subprocess.DEVNULL)
    shutil.copy(os.path.join(kinetics, "figures", "plies.png"), os.path.join(FIG, "hemi_kinetics_plies.png"))
    shutil.copy(os.path.join(kinetics, "figures", "crystallinity_ply_bottom.png"),
                os.path.join(FIG, "hemi_kinetics_crystallinity_ply_bottom.png"))
    strategies = runs["hemisphere_crystallisation_strategies"]
    subprocess.run([EXE, "report", strategies], check=True, stdout=subprocess.DEVNULL)
    subprocess.run([EXE, "report", os.path.join(strategies, "adi-8"), "--against", os.path.join(strategies, "shell2d")],
                   check=True, stdout=subprocess.DEVNULL)
    shutil.copy(os.path.join(strategies, "adi-8", "figures", "against", "plies.png"),
                os.path.join(FIG, "hemi_crystallisation_shell2d.png"))
    shutil.copy(os.path.join(strategies, "study.png"), os.path.join(FIG, "hemi_crystallisation_strategies.png"))
    for study, folder in runs.items():
        print("%s:" % study)
        print(open(os.path.join(folder, "study.csv")).read())


def conductivity(tmp):
    """The slab of ConductivityTable.CooledSlabAgainstAFineReference: one
    ply from 300 degC cooled through its top (h 1000 W/(m^2 K), 200 degC),
    k33 from 0.2 (200 degC) to 0.5 W/(m K) (300 degC), adi implicit with 16
    layers, against a 50-cell explicit reference with the exact Kirchhoff
    fluxes (written here), and the runs with k33 constant at either end."""
    h, rho_c = 0.0005, 1294.0 * 1775.0
    t0, k0, t1, k1 = 200.0, 0.2, 300.0, 0.5

    def K(T):  # int_t0^T k33, k33 held beyond the rows
        s = min(max(T, t0), t1) - t0
        return k0 * (min(T, t0) - t0) + k0 * s + 0.5 * (k1 - k0) / (t1 - t0) * s * s + k1 * max(T - t1, 0.0)

    n = 50
    e = h / n
    dt = 0.4 * rho_c * 0.5 * e / (2 * k1 / e + 1000.0)
    T = [300.0] * (n + 1)
    ref, t, marks = {}, 0.0, [1.0, 3.0, 6.0]
    while marks:
        q = [0.0] * (n + 1)
        for i in range(n):
            f = (K(T[i + 1]) - K(T[i])) / e
            q[i] += f
            q[i + 1] -= f
        q[n] += 1000.0 * (200.0 - T[n])
        T = [T[i] + dt * q[i] / (rho_c * (0.5 * e if i in (0, n) else e)) for i in range(n + 1)]
        t += dt
        if t >= marks[0] - 0.5 * dt:
            ref[marks.pop(0)] = list(T)
    runs = {}
    for label, k in (("rows", [[t0, 3.89, 0.31, k0], [t1, 3.89, 0.31, k1]]), ("k33 = 0.2", [3.89, 0.31, 0.2]),
                     ("k33 = 0.5", [3.89, 0.31, 0.5])):
        job = {"format": "thermostamp-job/1", "name": "slab", "time": {"end": 6.0},
               "materials": {"ply": {"density": 1294.0, "specific_heat": 1775.0, "conductivity": k}},
               "parts": [{"name": "ply", "mesh": {"generator": "rectangle", "origin": [0, 0, 0], "size": [0.01, 0.01],
                                                  "divisions": [2, 2]},
                          "thickness": h, "material": "ply", "initial_temperature": 300.0, "thickness_layers": 16}],
               "interactions": [{"type": "heat_exchange", "part": "ply", "face": "top", "h": 1000.0, "ambient": 200.0}],
               "solvers": {"mechanics": None, "thermal": {"splitter": "adi", "through_thickness": "implicit"}},
               "output": {"interval": 1.0, "fields": ["temperature"],
                          "probes": [{"name": "c", "part": "ply", "at": [0.005, 0.005, 0], "interval": 1.0,
                                      "quantities": ["temperature_profile"]}]}}
        path = os.path.join(tmp, "slab.json")
        with open(path, "w") as f:
            json.dump(job, f)
        out = os.path.join(tmp, "slab_" + label.replace(" ", ""))
        subprocess.run([EXE, "run", path, "--out", out, "--quiet"], check=True)
        runs[label] = profiles(out, "c")
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    zr = [(i / n - 0.5) * h * 1e3 for i in range(n + 1)]
    for j, tm in enumerate((1.0, 3.0, 6.0)):
        ax.plot(ref[tm], zr, "k-", lw=1, label="reference (50 cells)" if j == 0 else None)
        for label, style in (("rows", "C0o"), ("k33 = 0.2", "C1--"), ("k33 = 0.5", "C2:")):
            pts = sorted(closest(runs[label], tm))
            ax.plot([p[1] for p in pts], [p[0] * 1e3 for p in pts], style, ms=4,
                    label=("adi, " + label if label == "rows" else "adi, " + label + " W/(m K)") if j == 0 else None)
        ax.annotate("%g s" % tm, (ref[tm][-1], zr[-1]), textcoords="offset points", xytext=(4, -10), fontsize=8)
    ax.set_xlabel("temperature (degC)")
    ax.set_ylabel("z from mid-plane (mm)")
    ax.set_title("slab cooled on top, k33 from 0.2 (200 degC) to 0.5 W/(m K) (300 degC)", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(FIG, "conductivity_slab.png"), dpi=110)
    plt.close(fig)
    worst = max(abs(v - ref[tm][min(n, round((z / h + 0.5) * n))]) for tm in ref for z, v in closest(runs["rows"], tm)
                if abs((z / h + 0.5) * n - round((z / h + 0.5) * n)) < 1e-9)
    print("rows against the reference at the shared nodes: largest difference %.3f K" % worst)


def blank(tmp):
    """The cut patterns of the hemisphere cup cut at the die's opening
    (r = 80 mm), whole plies, for the UD fibres across the diagonal (the
    default job) and along y, and for the woven plies."""
    import math
    fig, axes = plt.subplots(1, 3, figsize=(15, 5.4))
    nests = []
    for ax, (job, title) in zip(axes, (("hemisphere_ud_2ply", "UD, fibres [1, -1, 0] (the default job)"),
                                       ("hemisphere_ud_2ply_fibres_y", "UD, fibres along y"),
                                       ("hemisphere_woven_2ply", "woven"))):
        out = os.path.join(tmp, job)
        subprocess.run([EXE, "run", os.path.join(ROOT, "share", "jobs", job + ".json"), "--out", out, "--quiet"],
                       check=True)
        subprocess.run([EXE, "blank", out, "--whole", "--trim", "cylinder:0,0,0,0,0,1,0.08", "--roll", "0.6", "--gap",
                        "0.005"], check=True, stdout=subprocess.DEVNULL)
        nests.append((out, title))
        info = json.load(open(os.path.join(out, "blank", "blank.json")))
        for ply, style in (("ply_top", "C3-"), ("ply_bottom", "C0--")):
            rows = [r for r in csv.DictReader(open(os.path.join(out, "blank", ply + ".csv"))) if r["kind"] == "pattern"]
            x = [1e3 * float(r["blank_x_m"]) for r in rows]
            y = [1e3 * float(r["blank_y_m"]) for r in rows]
            p = info["plies"][ply]
            ax.plot(x + x[:1], y + y[:1], style, lw=1.2,
                    label="%s: %.1f %% of the blank, r %.1f to %.1f mm"
                    % (ply, 100 * p["kept_share"], min(math.hypot(a, b) for a, b in zip(x, y)),
                       max(math.hypot(a, b) for a, b in zip(x, y))))
        t = [2 * math.pi * k / 200 for k in range(201)]
        ax.plot([80 * math.cos(a) for a in t], [80 * math.sin(a) for a in t], "k:", lw=0.8,
                label="r = 80 mm (the trim)")
        ax.set_aspect("equal")
        ax.set_xlim(-100, 100)
        ax.set_ylim(-100, 112)
        ax.grid(alpha=0.3)
        ax.set_xlabel("x in the blank (mm)")
        ax.set_ylabel("y in the blank (mm)")
        ax.set_title(title, fontsize=9)
        ax.legend(fontsize=7, loc="upper center")
    fig.tight_layout()
    fig.savefig(os.path.join(FIG, "hemi_blank_patterns.png"), dpi=110)
    plt.close(fig)
    # The top ply's pattern on a roll 600 mm wide, 5 mm apart, fibres along
    # the roll: the layouts blank writes (<ply>_nest.dxf).
    import ezdxf
    fig, axes = plt.subplots(3, 1, figsize=(10, 12))
    for ax, (out, title) in zip(axes, nests):
        n = json.load(open(os.path.join(out, "blank", "blank.json")))["plies"]["ply_top"]["nest"]
        msp = ezdxf.readfile(os.path.join(out, "blank", n["dxf"])).modelspace()
        for e in msp:
            if e.dxftype() == "LINE":
                ax.plot([e.dxf.start[0], e.dxf.end[0]], [e.dxf.start[1], e.dxf.end[1]], "k-", lw=1.5)
            elif e.dxftype() == "POLYLINE":
                pts = [(p[0], p[1]) for p in e.points()]
                pts.append(pts[0])
                ax.fill([p[0] for p in pts], [p[1] for p in pts], color="C0", alpha=0.25)
                ax.plot([p[0] for p in pts], [p[1] for p in pts], "C0-", lw=0.8)
        ax.set_aspect("equal")
        ax.set_xlim(-10, 1000 * n["drawn_length_m"] + 10)
        ax.set_ylim(-20, 620)
        ax.set_xlabel("along the roll, the fibres' direction (mm)")
        ax.set_ylabel("across (mm)")
        ax.set_title("%s, ply_top: %d lanes%s, pitch %.1f mm, %.1f mm of roll per pattern (all alike %.1f mm), "
                     "%.1f %% of the roll used"
                     % (title, n["lanes"], " of pairs" if n["pairs_turned_180"] else "", 1e3 * n["pitch_m"],
                        1e3 * n["roll_length_per_pattern_m"], 1e3 * n["alike_roll_length_per_pattern_m"],
                        100 * n["utilisation"]), fontsize=9)
        print("%s: %s" % (title, json.dumps(n)))
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(FIG, "hemi_nest.png"), dpi=90)
    plt.close(fig)


def yarn_lattice(path, width, nx, ny):
    """The bias specimen's mesh along the yarns, as the tests' write_yarn_lattice_gmsh."""
    a = width / ny
    ids, nodes = {}, []
    for j in range(ny + 1):
        for i in range(nx + 1):
            if (i + j) % 2 == 0:
                ids[(i, j)] = len(nodes)
                nodes.append((i * a, j * a))
    tris = []

    def add(p, q, r):
        t = [ids[p], ids[q], ids[r]]
        A, B, C = (nodes[k] for k in t)
        if (B[0] - A[0]) * (C[1] - A[1]) - (B[1] - A[1]) * (C[0] - A[0]) < 0:
            t[1], t[2] = t[2], t[1]
        tris.append(t)
    for j in range(ny + 1):
        for i in range(nx + 1):
            if (i + j) % 2 == 0:
                continue
            if i == 0:
                add((0, j - 1), (1, j), (0, j + 1))
            elif i == nx:
                add((nx, j - 1), (nx, j + 1), (nx - 1, j))
            else:
                if j < ny:
                    add((i - 1, j), (i + 1, j), (i, j + 1))
                if j > 0:
                    add((i - 1, j), (i, j - 1), (i + 1, j))
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from mesh_order import write_msh
    write_msh(path, nodes, tris)


def grippers(tmp):
    """The bias-extension specimen (Gripper.RigidJawsPullTheBiasSpecimenAsItsClampDoes)
    pulled by the test's clamp, by a gripper with rigid jaws and by one with
    flexible jaws: the central shear angle and the pulling force against the
    end's displacement, with the pin-jointed net."""
    import math
    H, W, ny, nx, ksh = 0.230, 0.115, 22, 44, (18.5, 46.4, -21.3)
    a, D = W / ny, 0.230 - 0.115
    mesh = os.path.join(tmp, "bias.msh")
    yarn_lattice(mesh, W, nx, ny)
    edge = [[H - 1e-6, -1, -1], [H + 1e-6, 1, 1]]
    base = {
        "format": "thermostamp-job/1", "name": "bias", "time": {"end": 0.33},
        "materials": {"woven": {"density": 1500.0, "membrane": {
            "law": "woven_hyperelastic", "k_warp": 1e5, "k_weft": 1e5, "k_sh": list(ksh)}}},
        "parts": [{"name": "specimen", "mesh": {"file": mesh}, "thickness": 0.0005, "material": "woven",
                   "fibre_direction": [1, 1, 0], "initial_temperature": 20.0}],
        "solvers": {"mechanics": {"dt_safety": 0.8, "damping": 10.0}, "thermal": None},
        "output": {"interval": 0.33, "fields": ["displacement"], "probes": [
            {"name": "centre", "part": "specimen", "at": [H / 2, W / 2 - a, 0], "quantities": ["shear_angle"],
             "interval": 0.0033},
            {"name": "end", "part": "specimen", "at": [H, W / 2 - a, 0], "quantities": ["displacement_x"],
             "interval": 0.0033}]}}
    held = {"type": "fix", "part": "specimen", "box": [[-1e-6, -1, -1], [1e-6, 1, 1]], "dofs": ["x", "y", "z"]}
    flat = {"type": "fix", "part": "*", "box": [[-1, -1, -1], [1, 1, 1]], "dofs": ["z"]}
    cases = {
        "the test's clamp (velocity)": [held, {"type": "velocity", "part": "specimen", "box": edge, "dofs": ["x"],
                                               "velocity": [0.1, 0, 0]},
                                        {"type": "fix", "part": "specimen", "box": edge, "dofs": ["y"]}, flat],
    }
    for jaws in ("rigid", "swivelling", "flexible"):
        cases["gripper, %s jaws" % jaws] = [held, {"type": "gripper", "name": "jaw", "part": "specimen", "box": edge,
                                                   "anchor": [H + 0.05, W / 2, 0], "stiffness": 1000.0, "jaws": jaws,
                                                   "anchor_motion": {"velocity": [0.1, 0, 0]}}, flat]

    def w(g):
        s = math.sin(g)
        return ksh[0] * s ** 2 + ksh[1] * s ** 4 + ksh[2] * s ** 6

    def gamma(u):
        return math.pi / 2 - 2 * math.acos((D + u) / (math.sqrt(2) * D))

    def e_of_gamma(g):
        return W * (H - 1.5 * W) * w(g) + W * W * w(g / 2)

    def net_force(u, g):  # dE/dgamma at the shear angle g times dgamma/du
        return (e_of_gamma(g + 1e-7) - e_of_gamma(g - 1e-7)) / 2e-7 * (gamma(u + 1e-6) - gamma(u - 1e-6)) / 2e-6
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    for (label, constraints), style in zip(cases.items(), ("k--", "C0-", "C2:", "C3-")):
        job = dict(base, constraints=constraints)
        if label.startswith("the test"):
            job["time"] = {"end": 0.26}
        path = os.path.join(tmp, "bias_%d.json" % len(label))
        with open(path, "w") as f:
            json.dump(job, f)
        out = os.path.join(tmp, "bias_%d" % len(label))
        subprocess.run([EXE, "run", path, "--out", out, "--quiet", "--threads", "1"], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        shear, u = {}, {}
        with open(os.path.join(out, "probes.csv")) as f:
            for r in csv.DictReader(f):
                (shear if r["quantity"] == "shear_angle" else u)[float(r["time"])] = float(r["value"])
        with open(os.path.join(out, "energy.csv")) as f:
            force = {float(r["time"]): float(r["reaction1_x"]) for r in csv.DictReader(f)}
        ts = sorted(t for t in u if t > 0)
        ax1.plot([u[t] * 1e3 for t in ts], [abs(shear[t]) for t in ts], style, label=label)
        tf = sorted(t for t in force if t > 0)
        ax2.plot([1e3 * u[min(u, key=lambda s: abs(s - t))] for t in tf], [force[t] for t in tf], style, lw=1,
                 label=label + ": force on the end")
        if label.startswith("gripper, rigid"):
            ax2.plot([u[t] * 1e3 for t in ts[4::5]], [net_force(u[t], abs(shear[t]) * math.pi / 180)
                                                      for t in ts[4::5]], "ko", ms=3,
                     label="pin-jointed net at the measured shear angle")
    us = [i * 0.0003 for i in range(1, 97)]
    ax1.plot([x * 1e3 for x in us], [gamma(x) * 180 / math.pi for x in us], "k:", label="pin-jointed net")
    ax1.set_xlabel("end displacement (mm)")
    ax1.set_ylabel("shear angle at the centre (deg)")
    ax2.set_xlabel("end displacement (mm)")
    ax2.set_ylabel("force (N)")
    ax2.set_ylim(0, 12)
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle("bias extension: the test's clamp, grippers with rigid, swivelling and flexible jaws")
    fig.tight_layout()
    fig.savefig(os.path.join(FIG, "gripper_bias.png"), dpi=90)
    plt.close(fig)


def swivelling(tmp):
    """Plates gripped whole by swivelling jaws (Gripper.SwivellingJaws*): a
    20 x 20 mm plate pulled along x at a corner, free and held by a `fix`
    at the opposite corner of its x edge (a pin), and with rigid jaws: the
    turn against time with the rigid body of the mesh's lumped masses
    (scipy's RK45 at 1e-10 relative tolerance)."""
    import math
    import numpy as np
    from scipy.integrate import solve_ivp
    a, P, rho_h, t_end, n = 0.02, 0.01, 1294.0 * 0.0005, 0.025, 4
    # Lumped masses of the crossed pattern: corners of a cell a quarter
    # turn of its 4 triangles, the centre node a third of the cell.
    h = a / n
    nodes = {}
    for j in range(n):
        for i in range(n):
            c = ((i + 0.5) * h, (j + 0.5) * h)
            nodes[c] = nodes.get(c, 0) + rho_h * h * h / 3
            for dx, dy in ((0, 0), (1, 0), (1, 1), (0, 1)):
                k = ((i + dx) * h, (j + dy) * h)
                nodes[k] = nodes.get(k, 0) + rho_h * h * h / 6
    M = sum(nodes.values())

    def job(name, pin, jaws):
        j = {"format": "thermostamp-job/1", "name": name, "time": {"end": t_end},
             "materials": {"ud": {"density": 1294.0, "membrane": {
                 "law": "ud_hyperelastic", "k_fibre": 5.0e4, "p_ct": 5.0e3, "k_sh": [2.0e3, 0.0, 0.0]}}},
             "parts": [{"name": "plate", "mesh": {"generator": "rectangle", "origin": [0, 0, 0], "size": [a, a],
                                                  "divisions": [n, n], "pattern": "crossed"},
                        "thickness": 0.0005, "material": "ud", "initial_temperature": 280.0}],
             "constraints": [
                 {"type": "gripper", "name": "jaws", "part": "plate", "box": [[-1, -1, -1], [1, 1, 1]],
                  "anchor": [a / 2, a / 2 + 1.0, 0], "stiffness": 1e-9, "jaws": jaws},
                 {"type": "gripper", "name": "pull", "part": "plate", "box": [[a - 1e-6, a - 1e-6, -1],
                                                                              [a + 1e-6, a + 1e-6, 1]],
                  "anchor": [a + 100.0, a, 0], "stiffness": 1e-9, "preload": P}],
             "solvers": {"mechanics": {"dt_safety": 0.8}, "thermal": None},
             "output": {"interval": t_end, "fields": ["displacement"], "probes": [
                 {"name": "c%d" % c, "part": "plate", "at": at, "quantities": ["displacement_x", "displacement_y"],
                  "interval": t_end / 50} for c, at in enumerate(([0, 0, 0], [a, a, 0]))]}}
        if pin:
            j["constraints"].append({"type": "fix", "part": "plate", "box": [[-1e-6, -1e-6, -1], [1e-6, 1e-6, 1]],
                                     "dofs": ["x", "y", "z"]})
        path = os.path.join(tmp, name + ".json")
        with open(path, "w") as f:
            json.dump(j, f)
        out = os.path.join(tmp, name)
        subprocess.run([EXE, "run", path, "--out", out, "--quiet", "--threads", "1"], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        u = {}
        with open(os.path.join(out, "probes.csv")) as f:
            for r in csv.DictReader(f):
                u.setdefault(float(r["time"]), {})[(r["probe"], r["quantity"])] = float(r["value"])
        ts = sorted(u)
        turn = [math.atan2(a + u[t][("c1", "displacement_y")] - u[t][("c0", "displacement_y")],
                           a + u[t][("c1", "displacement_x")] - u[t][("c0", "displacement_x")]) - math.pi / 4
                for t in ts]
        return np.array(ts), np.array(turn)

    def reference(pin):
        ctr = np.array([0.0, 0.0]) if pin else np.array([a / 2, a / 2])
        I = sum(m * ((x - ctr[0]) ** 2 + (y - ctr[1]) ** 2) for (x, y), m in nodes.items())
        r0 = np.array([a, a]) - ctr

        def rate(t, y):  # theta, omega, cx, cy, vx, vy
            c, s = math.cos(y[0]), math.sin(y[0])
            r = np.array([c * r0[0] - s * r0[1], s * r0[0] + c * r0[1]])
            pt = ctr + (0 if pin else y[2:4]) + r
            f = np.array([a + 100.0, a]) - pt
            f *= P / np.linalg.norm(f)
            acc = [0.0, 0.0] if pin else list(f / M)
            return [y[1], (r[0] * f[1] - r[1] * f[0]) / I, y[4], y[5]] + acc
        ts = np.linspace(0, t_end, 200)
        sol = solve_ivp(rate, (0, t_end), [0, 0, 0, 0, 0, 0], t_eval=ts, rtol=1e-10, atol=1e-14)
        return ts, sol.y[0]

    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    for name, pin, jaws, style in (("free", False, "swivelling", "C0o"), ("pin", True, "swivelling", "C2o"),
                                   ("rigid", False, "rigid", "C3s")):
        t, th = job(name, pin, jaws)
        label = {"free": "swivelling jaws, free", "pin": "swivelling jaws, on a pin at (0, 0)",
                 "rigid": "rigid jaws"}[name]
        ax.plot(t * 1e3, np.degrees(th), style, ms=3, label=label)
        if jaws == "swivelling":
            tr, thr = reference(pin)
            ax.plot(tr * 1e3, np.degrees(thr), "k-", lw=0.8, label="rigid body, RK45" if not pin else None)
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("turn of the plate (deg)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("a plate gripped whole, pulled at its corner (a, a) along x by 0.01 N", fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(FIG, "gripper_swivel.png"), dpi=90)
    plt.close(fig)


def main():
    os.makedirs(FIG, exist_ok=True)
    tmp = tempfile.mkdtemp()
    if "--grippers" in sys.argv:
        grippers(tmp)
        swivelling(tmp)
        shutil.rmtree(tmp)
        print("figures written to", FIG)
        return
    if "--blank" in sys.argv:
        blank(tmp)
        shutil.rmtree(tmp)
        print("figures written to", FIG)
        return
    if "--conductivity" in sys.argv:
        conductivity(tmp)
        shutil.rmtree(tmp)
        print("figures written to", FIG)
        return
    if "--crystallisation" in sys.argv:
        crystallisation(tmp)
        shutil.rmtree(tmp)
        print("figures written to", FIG)
        return
    ver = os.path.join(ROOT, "share", "verification")
    for study in ("slab_robin_study", "patch_study", "hemisphere_study"):
        out = os.path.join(tmp, study)
        threads = "2" if study == "hemisphere_study" else "1"  # the scene's mechanics run on both cores
        subprocess.run([EXE, "study", os.path.join(ver, study + ".json"), "--out", out, "--quiet", "--threads", threads],
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        shutil.copy(os.path.join(out, "study.png"), os.path.join(FIG, study + ".png"))
        shutil.copy(os.path.join(out, "study.csv"), os.path.join(FIG, study + ".csv"))
    # Patch case: profiles at the patch edge and centre, adi / layered3d / shell2d.
    base = os.path.join(tmp, "patch_study")
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2), sharey=True)
    for ax, probe in zip(axes, ("upper_centre", "upper_edge")):
        for label, style in (("reference", "k-"), ("adi-8", "C0o-"), ("adi-8-layers", "C3^-"), ("layered3d-8", "C1s--"),
                             ("shell2d", "C2:")):
            d = profiles(os.path.join(base, label), probe)
            for t, alpha in ((0.5, 0.5), (2.0, 1.0)):
                pts = sorted(closest(d, t))
                ax.plot([p[1] for p in pts], [p[0] * 1e3 for p in pts], style, alpha=alpha, ms=3,
                        label="%s, t = %g s" % ("layered3d-32 (reference)" if label == "reference" else label, t))
        ax.set_title("probe %s (upper ply)" % probe)
        ax.set_xlabel("temperature (degC)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("z from mid-plane (mm)")
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(FIG, "patch_profiles.png"), dpi=110)
    plt.close(fig)
    # Demo job figures.
    demo = os.path.join(tmp, "demo")
    subprocess.run([EXE, "run", os.path.join(ROOT, "share", "jobs", "two_ply_thermal_demo.json"), "--out", demo,
                    "--quiet"], check=True)
    subprocess.run([EXE, "report", demo], check=True, stdout=subprocess.DEVNULL)
    for name in ("map_ply_top.png", "map_ply_bottom.png", "profile_centre_top.png", "profile_centre_bottom.png"):
        shutil.copy(os.path.join(demo, "figures", name), os.path.join(FIG, "demo_" + name))
    hemisphere_conductance(tmp)
    shutil.rmtree(tmp)
    print("figures written to", FIG)


if __name__ == "__main__":
    main()
