#!/usr/bin/env python3
"""Contact benchmark: cost of penalty_node_surface per node per cycle, for a
stack of two plies on a plane die (one tool pair, one ply/ply pair searched
in both directions), 10k to 1M nodes per ply, 1 and 2 threads; and the
time breakdown of the hemisphere scene, with the bare membrane loop of
mechanics.py on as many elements (1800) timed just before each run as the
yardstick of the machine's speed at that moment.

With the ply/ply search every step the table gives it with and without
`prune_search`. The plies' meshes lie node over node by default, so the
candidates of a node tie and pruning skips few; --offset shifts the upper
ply by a third of a cell in x and half a cell in y, so that its nodes lie
inside the lower ply's triangles, as in a formed stack.
Usage: scripts/bench/contact.py [--quick] [--offset] (after a Release build).
"""
import json
import os
import subprocess
import sys
import tempfile

from mechanics import bare_membrane

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXE = os.environ.get("THERMOSTAMP_EXE", os.path.join(ROOT, "build", "bin", "thermostamp"))
H = 0.0005


def job(n, cycles, search_interval=1, prune=True, offset=False):
    size = n * 0.002
    cell = size / (n - 1)
    dt = 2e-6
    shift = (cell / 3, cell / 2) if offset else (0.0, 0.0)
    ply = lambda name, z, o: {"name": name, "thickness": H, "material": "ud", "fibre_direction": [1, 0, 0],
                              "mesh": {"generator": "rectangle", "origin": [o[0], o[1], z], "size": [size, size],
                                       "divisions": [n - 1, n - 1]}, "initial_temperature": 280.0}
    return {
        "format": "thermostamp-job/1", "name": "bench_contact", "time": {"end": cycles * dt},
        "materials": {"ud": {"density": 1294.0,
                             "membrane": {"law": "ud_hyperelastic", "k_fibre": 1.0e5, "p_ct": 50.0, "k_sh": [18.5, 0, 0]}}},
        "parts": [ply("low", 0.5 * H, (0.0, 0.0)), ply("up", 1.5 * H, shift)],
        "tools": [{"name": "die", "surface": {"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 1]}}],
        "interactions": [{"type": "contact", "between": ["die", "low"], "friction": 0.2},
                         {"type": "contact", "between": ["up", "low"], "friction": 0.2,
                          "search_interval": search_interval, "prune_search": prune}],
        # contact in its own parallel loops (not beside the elements), so that its cost on 2 threads is its own
        "solvers": {"mechanics": {"dt_safety": 0.8, "mass_scaling": {"target_dt": dt}, "gravity": [0, 0, -9.81],
                                  "contact_schedule": "in_turn"},
                    "thermal": None},
        "output": {"interval": cycles * dt, "fields": ["displacement"], "checkpoint_at_end": False,
                   "series_interval": cycles * dt},
    }


def run(path_or_job, threads, extra=()):
    with tempfile.TemporaryDirectory() as d:
        path = path_or_job
        if isinstance(path_or_job, dict):
            path = os.path.join(d, "job.json")
            json.dump(path_or_job, open(path, "w"))
        out = os.path.join(d, "out")
        subprocess.run([EXE, "run", path, "--out", out, "--threads", str(threads), "--quiet", *extra], check=True)
        return json.load(open(os.path.join(out, "summary.json")))


def main():
    quick = "--quick" in sys.argv
    offset = "--offset" in sys.argv
    sizes = [100, 316] if quick else [100, 316, 1000]
    print("### Contact (penalty_node_surface), two plies on a die, cost per ply node per cycle (%s)\n"
          % ("upper ply offset by (1/3, 1/2) cell" if offset else "plies node over node"))
    print("| nodes per ply | ply/ply search_interval | prune_search | threads | cycles | contact (s) | contact ns per node-cycle | elements ns per element-cycle |")
    print("|---|---|---|---|---|---|---|---|")
    for n in sizes:
        cycles = 200 if n < 1000 else 40
        for interval, prune in ((1, True), (1, False), (64, True)):
            for th in (1, 2):
                s = run(job(n, cycles, interval, prune, offset), th)
                cyc = s["steps"]["mechanics"]
                nodes = 2 * n * n
                elems = 2 * 2 * (n - 1) ** 2
                t = s["timing_s"]
                print("| %d | %d | %s | %d | %d | %.3f | %.1f | %.1f |" % (
                    n * n, interval, "true" if prune else "false" if interval == 1 else "(off)", th, cyc,
                    t["contact"], t["contact"] / (nodes * cyc) * 1e9, t["elements_and_laws"] / (elems * cyc) * 1e9),
                      flush=True)
    print("\n### Hemisphere scene (share/jobs/hemisphere_ud_2ply.json), time breakdown\n")
    print("| threads | wall time (s) | cycles | elements and laws | contact | thermal | integration and audit | output | ns per element-cycle (all) | bare loop (ns) | in bare loops |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    scene = os.path.join(ROOT, "share", "jobs", "hemisphere_ud_2ply.json")
    for th in (1, 2):
        extra = ("--set", "time.end=1.0") if quick else ()
        bare = bare_membrane(30, 100000)  # 2 x 30 x 30 = 1800 elements, the scene's count
        s = run(scene, th, extra)
        t = s["timing_s"]
        cyc = s["steps"]["mechanics"]
        elems = sum(p["elements"] for p in s["parts"])
        ns = s["wall_time_s"] / (elems * cyc) * 1e9
        print("| %d | %.1f | %d | %.1f s | %.1f s | %.1f s | %.1f s | %.2f s | %.0f | %.1f | %.1f |" % (
            th, s["wall_time_s"], cyc, t["elements_and_laws"], t["contact"], t["thermal"],
            t["time_integration_and_audit"], t["output"], ns, bare, ns / bare))


if __name__ == "__main__":
    main()
