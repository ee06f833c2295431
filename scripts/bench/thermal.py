#!/usr/bin/env python3
"""Thermal benchmarks: cost of the adi splitter per node-layer-step against
mesh size and threads, and adi against layered3d on the contact patch.

Usage: scripts/bench/thermal.py [--quick] [--specific-heat | --crystallisation | --melting | --conductivity]
(after a Release build in build/)
--specific-heat runs only the comparison of a constant specific heat with
a table whose peak the plate cools through; --crystallisation only the
comparison of a plate without crystallisation kinetics with plates whose
every value crystallises at every step (the rate from rows, and from
the Gaussian); --melting only the comparison of a plate heated without
kinetics, with kinetics whose rate is zero there, and with kinetics whose
every value melts at every step (melting rows from 250 to 350 degC, a
crystalline plate heated from 250 degC); --conductivity only the
comparison of a constant conductivity with rows (the mean operator in
plane, and every layer's own), on one ply and on two linked plies.
Prints Markdown tables (copied into docs/benchmarks.md).
"""
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXE = os.environ.get("THERMOSTAMP_EXE", os.path.join(ROOT, "build", "bin", "thermostamp"))


# A specific heat table whose peak the benchmark plate (300 degC, sinks at
# 250-260 degC) cools through.
PEAK_ROWS = [[280.0, 1775.0], [290.0, 3775.0], [300.0, 1775.0]]


# Crystallisation kinetics with a rate above zero at every temperature of
# the plate (every value takes the kinetics' full path at every step).
KINETICS = {
    "rows": {"latent_heat": 30000.0, "avrami_exponent": 3.0, "rate": [[200.0, 2.0], [320.0, 1.0]]},
    "gaussian": {"latent_heat": 30000.0, "avrami_exponent": 3.0,
                 "rate": {"k_max": 2.0, "t_max": 280.0, "half_width": 50.0}},
}


# Kinetics whose rate is zero above 160 degC, without and with melting rows
# over the whole range the heated plate crosses (every value melts at
# every step), starting fully crystalline.
MELTING = {
    "zero_rate": {"latent_heat": 30000.0, "avrami_exponent": 3.0, "rate": [[150.0, 1.0], [160.0, 0.0]], "initial": 1.0},
    "melting": {"latent_heat": 30000.0, "avrami_exponent": 3.0, "rate": [[150.0, 1.0], [160.0, 0.0]], "initial": 1.0,
                "melting": [[250.0, 1.0], [280.0, 0.7], [320.0, 0.2], [350.0, 0.0]]},
}


# A conductivity that follows the temperature over the plate's range.
K_ROWS = [[240.0, 3.5, 0.25, 0.25], [300.0, 3.89, 0.31, 0.35]]


def plate_job(divisions, layers, splitter, steps, dt, linked=False, specific_heat=1775.0, crystallisation=None,
              heated=False, conductivity=(3.89, 0.31, 0.31), in_plane=None):
    size = divisions * 0.001  # 1 mm elements
    part = {
        "name": "ply", "thickness": 0.0005, "material": "m", "fibre_direction": [1, 1, 0],
        "mesh": {"generator": "rectangle", "origin": [0, 0, 0.00025], "size": [size, size],
                 "divisions": [divisions, divisions]},
        "initial_temperature": 300.0, "thickness_layers": layers,
    }
    if heated:  # from 250 degC, heated on both faces from 400 degC
        part["initial_temperature"] = 250.0
    parts = [part]
    inter = [
        {"type": "heat_exchange", "part": "ply", "face": "top", "h": 1000.0, "ambient": 260.0,
         "region": {"circle": {"centre": [0, 0], "radius": size / 2}}},
        {"type": "heat_exchange", "part": "ply", "face": "bottom", "h": 500.0, "ambient": 250.0},
    ]
    if heated:
        inter = [{"type": "heat_exchange", "part": "ply", "face": face, "h": 1000.0, "ambient": 400.0}
                 for face in ("top", "bottom")]
    if linked:
        upper = dict(part, name="upper", mesh=dict(part["mesh"], origin=[0, 0, 0.00075]))
        parts.append(upper)
        inter = [{"type": "contact", "handler": "penalty_node_surface", "between": ["upper", "ply"],
                  "conductance": 1000.0},
                 {"type": "heat_exchange", "part": "upper", "face": "top", "h": 1000.0, "ambient": 260.0},
                 {"type": "heat_exchange", "part": "ply", "face": "bottom", "h": 500.0, "ambient": 250.0}]
    material = {"density": 1294.0, "specific_heat": specific_heat, "conductivity": list(conductivity)}
    if crystallisation:
        material["crystallisation"] = crystallisation
    thermal = {"splitter": splitter, "through_thickness": "implicit", "dt": dt}
    if in_plane:
        thermal["in_plane"] = in_plane
    return {
        "format": "thermostamp-job/1", "name": "bench",
        "time": {"end": steps * dt},
        "materials": {"m": material},
        "parts": parts, "interactions": inter,
        "solvers": {"mechanics": None, "thermal": thermal},
        "output": {"interval": steps * dt, "fields": ["temperature_mean"], "checkpoint_at_end": False},
    }


def run(job, threads):
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "job.json")
        json.dump(job, open(path, "w"))
        out = os.path.join(d, "out")
        subprocess.run([EXE, "run", path, "--out", out, "--threads", str(threads), "--quiet"], check=True)
        return json.load(open(os.path.join(out, "summary.json")))


def three_way(sizes, layers, steps, title, header, variants):
    """A table of the ns per node-layer-step of a plate (n divisions) and of
    two variants of it, variants(n) giving the three jobs, with the ratios
    of the variants to the first, on 1 and 2 threads."""
    print(title)
    print(header)
    print("|---|---|---|---|---|---|---|")
    for n in sizes:
        for th in (1, 2):
            nodes = (n + 1) ** 2
            per = nodes * (layers + 1) * steps / 1e9
            a, b, c = (run(job, th)["wall_time_s"] for job in variants(n))
            print("| %d | %d | %.2f | %.2f | %.2f | %.2f | %.2f |" % (nodes, th, a / per, b / per, b / a, c / per, c / a))


def main():
    quick = "--quick" in sys.argv
    sizes = [100, 316] if quick else [100, 316, 1000]
    layers, steps, dt = 16, 20, 0.01
    if "--specific-heat" in sys.argv:
        print("### adi (implicit), a constant specific heat against rows %s, %d layers, %d steps\n"
              % (PEAK_ROWS, layers, steps))
        print("| nodes | threads | constant: wall (s) | ns per node-layer-step | table: wall (s) | ns per node-layer-step | ratio |")
        print("|---|---|---|---|---|---|---|")
        for n in sizes:
            for th in (1, 2):
                nodes = (n + 1) ** 2
                a = run(plate_job(n, layers, "adi", steps, dt), th)
                b = run(plate_job(n, layers, "adi", steps, dt, specific_heat=PEAK_ROWS), th)
                per = nodes * (layers + 1) * steps / 1e9
                print("| %d | %d | %.3f | %.2f | %.3f | %.2f | %.2f |" % (
                    nodes, th, a["wall_time_s"], a["wall_time_s"] / per, b["wall_time_s"], b["wall_time_s"] / per,
                    b["wall_time_s"] / a["wall_time_s"]))
        return
    if "--crystallisation" in sys.argv:
        three_way(sizes, layers, steps,
                  "### adi (implicit), without crystallisation kinetics and with them (every value crystallising), "
                  "%d layers, %d steps\n" % (layers, steps),
                  "| nodes | threads | without: ns per node-layer-step | rate from rows: ns | ratio | Gaussian rate: ns | ratio |",
                  lambda n: [plate_job(n, layers, "adi", steps, dt),
                             plate_job(n, layers, "adi", steps, dt, crystallisation=KINETICS["rows"]),
                             plate_job(n, layers, "adi", steps, dt, crystallisation=KINETICS["gaussian"])])
        return
    if "--melting" in sys.argv:
        three_way(sizes, layers, steps,
                  "### adi (implicit), a crystalline plate heated from 250 degC: without kinetics, with kinetics whose "
                  "rate is zero there, and with melting rows (every value melting at every step), %d layers, %d steps\n"
                  % (layers, steps),
                  "| nodes | threads | without: ns per node-layer-step | zero rate: ns | ratio | melting: ns | ratio |",
                  lambda n: [plate_job(n, layers, "adi", steps, dt, heated=True),
                             plate_job(n, layers, "adi", steps, dt, crystallisation=MELTING["zero_rate"], heated=True),
                             plate_job(n, layers, "adi", steps, dt, crystallisation=MELTING["melting"], heated=True)])
        return
    if "--conductivity" in sys.argv:
        print("### adi (implicit), a constant conductivity against rows %s, one ply, %d layers, %d steps\n"
              % (K_ROWS, layers, steps))
        print("| nodes | threads | in_plane mean, constant: ns per node-layer-step | rows: ns | ratio "
              "| in_plane layers, constant: ns | rows: ns | ratio |")
        print("|---|---|---|---|---|---|---|---|")
        for n in sizes:
            for th in (1, 2):
                nodes = (n + 1) ** 2
                per = nodes * (layers + 1) * steps / 1e9
                a, b, c, d = (run(plate_job(n, layers, "adi", steps, dt, conductivity=k, in_plane=mode), th)["wall_time_s"]
                              for mode in ("mean", "layers") for k in ((3.89, 0.31, 0.31), K_ROWS))
                print("| %d | %d | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f |"
                      % (nodes, th, a / per, b / per, b / a, c / per, d / per, d / c))
        print()
        print("### two plies in full contact (linked rods), constant conductivity against rows, %d layers, %d steps, "
              "1 thread\n" % (layers, steps))
        print("| nodes | splitter | constant: ns per node-layer-step | rows: ns | ratio |")
        print("|---|---|---|---|---|")
        for n in sizes[:2]:
            for sp in ("adi", "layered3d"):
                nodes = 2 * (n + 1) ** 2
                per = nodes * (layers + 1) * steps / 1e9
                a = run(plate_job(n, layers, sp, steps, dt, linked=True), 1)["wall_time_s"]
                b = run(plate_job(n, layers, sp, steps, dt, linked=True, conductivity=K_ROWS), 1)["wall_time_s"]
                print("| %d | %s | %.2f | %.2f | %.2f |" % (nodes, sp, a / per, b / per, b / a))
        return
    print("### adi (implicit) cost per node-layer-step, one ply, %d layers, %d steps\n" % (layers, steps))
    print("| nodes | threads | wall time (s) | ns per node-layer-step | speed-up |")
    print("|---|---|---|---|---|")
    for n in sizes:
        base = None
        for th in (1, 2):
            s = run(plate_job(n, layers, "adi", steps, dt), th)
            nodes = (n + 1) ** 2
            ns = s["wall_time_s"] / (nodes * (layers + 1) * s["steps"]["thermal"]) * 1e9
            base = base or s["wall_time_s"]
            print("| %d | %d | %.3f | %.2f | %.2f |" % (nodes, th, s["wall_time_s"], ns, base / s["wall_time_s"]))
    print()
    print("### two plies in full contact (linked rods), %d layers, %d steps, 1 thread\n" % (layers, steps))
    print("| nodes | splitter | wall time (s) | ns per node-layer-step |")
    print("|---|---|---|---|")
    for n in sizes[:2]:
        for sp in ("adi", "layered3d"):
            s = run(plate_job(n, layers, sp, steps, dt, linked=True), 1)
            nodes = 2 * (n + 1) ** 2
            ns = s["wall_time_s"] / (nodes * (layers + 1) * s["steps"]["thermal"]) * 1e9
            print("| %d | %s | %.3f | %.2f |" % (nodes, sp, s["wall_time_s"], ns))
    print()
    print("### contact patch study (share/verification/patch_study.json)\n")
    with tempfile.TemporaryDirectory() as d:
        subprocess.run([EXE, "study", os.path.join(ROOT, "share", "verification", "patch_study.json"),
                        "--out", d, "--quiet", "--threads", "1"], check=True, stdout=subprocess.DEVNULL)
        rows = [l.strip().split(",") for l in open(os.path.join(d, "study.csv"))]
    head = rows[0]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r in rows[1:]:
        print("| " + " | ".join(r) + " |")


if __name__ == "__main__":
    main()
