#!/usr/bin/env python3
"""Cost of a gripper's jaws: the hemisphere scene held by four grippers
(share/jobs/hemisphere_ud_2ply_grippers.json) with their jaws flexible,
rigid and swivelling, the first --end seconds of stroke with
`contact_schedule` `by_part`, the three kinds in turn --reps times. The
jaws' ties are part of the time integration (`timing_s.time_integration_and_audit` of
summary.json); the table gives its smallest time per kind and the cost per
step over the flexible jaws'.

Usage: scripts/bench/jaws.py [--threads N] [--end T] [--reps N]
(after a Release build: cmake -S . -B build -DCMAKE_BUILD_TYPE=Release).
"""
import argparse
import json
import os
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
KINDS = ("flexible", "rigid", "swivelling")


def run(kind, threads, end, out):
    cmd = [os.path.join(ROOT, "build", "bin", "thermostamp"), "run",
           os.path.join(ROOT, "share", "jobs", "hemisphere_ud_2ply_grippers.json"), "--out", out, "--threads",
           str(threads), "--quiet", "--set", "time.end=%g" % end, "--set",
           'solvers.mechanics.contact_schedule="by_part"']
    for c in range(2, 6):
        cmd += ["--set", 'constraints.%d.jaws="%s"' % (c, kind)]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    return s["timing_s"]["time_integration_and_audit"], s["wall_time_s"], s["steps"]["mechanics"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--end", type=float, default=0.5)
    ap.add_argument("--reps", type=int, default=3)
    a = ap.parse_args()
    best = {k: (float("inf"), float("inf"), 0) for k in KINDS}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(a.reps):
            for k in KINDS:
                r = run(k, a.threads, a.end, os.path.join(tmp, k))
                best[k] = (min(best[k][0], r[0]), min(best[k][1], r[1]), r[2])
    base = best["flexible"]
    print("| jaws | threads | steps | integration (s) | wall (s) | integration over flexible (us a step) |")
    print("| --- | --- | --- | --- | --- | --- |")
    for k in KINDS:
        i, w, n = best[k]
        print("| %s | %d | %d | %.3f | %.2f | %+.2f |" % (k, a.threads, n, i, w, 1e6 * (i - base[0]) / n))


if __name__ == "__main__":
    main()
