#!/usr/bin/env python3
"""Paired comparison of two builds on one job: both run at the same time,
one thread each, pinned to different cores (swapped at every repetition),
so that they share whatever else the machine is doing. Prints, per pair,
the times of B over those of A (wall, elements and laws, contact,
integration and audit) and the median ratios.

Usage:
  scripts/bench/compare.py EXE_A EXE_B JOB [--reps N] [--set path=value ...]

EXE_A and EXE_B are `thermostamp` executables (e.g. a copy of build/bin with
its plugins, taken before a change, and the current build/bin/thermostamp).
Needs two cores and `taskset`. A ratio below 1 means B is faster.
"""
import argparse
import json
import os
import statistics
import subprocess
import tempfile

KEYS = ("elements_and_laws", "contact", "time_integration_and_audit")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("exe_a")
    ap.add_argument("exe_b")
    ap.add_argument("job")
    ap.add_argument("--reps", type=int, default=4)
    ap.add_argument("--set", action="append", default=[], help="passed to both runs")
    args = ap.parse_args()
    extra = sum((["--set", s] for s in args.set), [])
    ratios = {k: [] for k in ("wall",) + KEYS}
    with tempfile.TemporaryDirectory() as d:
        print("| pair | A wall (s) | B wall (s) | wall B/A | elements B/A | contact B/A | integration B/A |")
        print("|---|---|---|---|---|---|---|")
        for r in range(args.reps):
            cores = (0, 1) if r % 2 == 0 else (1, 0)
            procs, outs = [], []
            for exe, core, tag in ((args.exe_a, cores[0], "a"), (args.exe_b, cores[1], "b")):
                out = os.path.join(d, "%s%d" % (tag, r))
                outs.append(out)
                cmd = ["taskset", "-c", str(core), exe, "run", args.job, "--out", out, "--threads", "1", "--quiet"] + extra
                procs.append(subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
            for p in procs:
                if p.wait() != 0:
                    raise SystemExit("a run failed: %s" % " ".join(p.args))
            a, b = (json.load(open(os.path.join(o, "summary.json"))) for o in outs)
            row = {"wall": b["wall_time_s"] / a["wall_time_s"]}
            for k in KEYS:
                ta, tb = a["timing_s"][k], b["timing_s"][k]
                row[k] = tb / ta if ta > 0 else float("nan")
            for k, v in row.items():
                ratios[k].append(v)
            print("| %d | %.2f | %.2f | %.3f | %.3f | %.3f | %.3f |" % (
                r + 1, a["wall_time_s"], b["wall_time_s"], row["wall"], row["elements_and_laws"], row["contact"],
                row["time_integration_and_audit"]))
    print("\nmedian B/A: wall %.3f, elements %.3f, contact %.3f, integration %.3f" % tuple(
        statistics.median(ratios[k]) for k in ("wall",) + KEYS))


if __name__ == "__main__":
    main()
