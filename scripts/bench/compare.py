#!/usr/bin/env python3
"""Paired comparison of two builds on one job, one thread each. By default
both run at the same time, pinned to different cores (swapped at every
repetition), so that they share whatever else the machine is doing; on
large parts they then also share the memory bandwidth, which a run alone
does not. With --in-turn they run one after the other (the order swapped
at every repetition), each with the machine to itself: the regime of the
one-thread benchmark; use short jobs and many repetitions, so that both
runs of a pair see the machine in the same state. Prints, per pair, the
times of B over those of A (wall; the time loop: elements and laws,
contact, integration and audit; and each of those) and the median ratios,
then the smallest loop time of each per element-cycle where the job has
one part.

Usage:
  scripts/bench/compare.py EXE_A EXE_B JOB [--reps N] [--in-turn] [--set path=value ...]

EXE_A and EXE_B are `thermostamp` executables (e.g. a copy of build/bin with
its plugins, taken before a change, and the current build/bin/thermostamp).
Needs two cores and `taskset` (not with --in-turn). A ratio below 1 means
B is faster.
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
    ap.add_argument("--in-turn", action="store_true", help="one run after the other instead of both at once")
    ap.add_argument("--set", action="append", default=[], help="passed to both runs")
    args = ap.parse_args()
    extra = sum((["--set", s] for s in args.set), [])
    ratios = {k: [] for k in ("wall", "loop") + KEYS}
    loop_ns = {"a": [], "b": []}
    with tempfile.TemporaryDirectory() as d:
        print("| pair | A wall (s) | B wall (s) | wall B/A | loop B/A | elements B/A | contact B/A | integration B/A |")
        print("|---|---|---|---|---|---|---|---|")
        for r in range(args.reps):
            cores = (0, 1) if r % 2 == 0 else (1, 0)
            runs = [(args.exe_a, cores[0], "a"), (args.exe_b, cores[1], "b")]
            if args.in_turn and r % 2 == 1:
                runs.reverse()
            procs, outs = [], {}
            for exe, core, tag in runs:
                outs[tag] = os.path.join(d, "%s%d" % (tag, r))
                cmd = [exe, "run", args.job, "--out", outs[tag], "--threads", "1", "--quiet"] + extra
                if not args.in_turn:
                    cmd = ["taskset", "-c", str(core)] + cmd
                procs.append(subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
                if args.in_turn and procs[-1].wait() != 0:
                    raise SystemExit("a run failed: %s" % " ".join(procs[-1].args))
            for p in procs:
                if p.wait() != 0:
                    raise SystemExit("a run failed: %s" % " ".join(p.args))
            a, b = (json.load(open(os.path.join(outs[t], "summary.json"))) for t in ("a", "b"))
            row = {"wall": b["wall_time_s"] / a["wall_time_s"]}
            loop = {t: sum(s["timing_s"][k] for k in KEYS) for t, s in (("a", a), ("b", b))}
            row["loop"] = loop["b"] / loop["a"]
            for k in KEYS:
                ta, tb = a["timing_s"][k], b["timing_s"][k]
                row[k] = tb / ta if ta > 0 else float("nan")
            for k, v in row.items():
                ratios[k].append(v)
            for t, s in (("a", a), ("b", b)):
                cycles = s["steps"]["mechanics"]
                if len(s["parts"]) == 1 and cycles > 0:
                    loop_ns[t].append(loop[t] / (cycles * s["parts"][0]["elements"]) * 1e9)
            print("| %d | %.2f | %.2f | %.3f | %.3f | %.3f | %.3f | %.3f |" % (
                r + 1, a["wall_time_s"], b["wall_time_s"], row["wall"], row["loop"], row["elements_and_laws"],
                row["contact"], row["time_integration_and_audit"]))
    print("\nmedian B/A: wall %.3f, loop %.3f, elements %.3f, contact %.3f, integration %.3f" % tuple(
        statistics.median(ratios[k]) for k in ("wall", "loop") + KEYS))
    if loop_ns["a"] and loop_ns["b"]:
        print("smallest loop time per element-cycle: A %.1f ns, B %.1f ns" % (min(loop_ns["a"]), min(loop_ns["b"])))


if __name__ == "__main__":
    main()
