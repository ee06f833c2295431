#!/usr/bin/env python3
"""Robustness sweep: every number of a job set in turn to extreme values
(0, -1, 1e30, 1e-30, 3.5 by default), each variant run for a short time;
the run must end with exit 0 (ran), 2 (refused as input, before running)
or 3 (stopped with a message), within the timeout. Anything else (a crash,
a signal, a hang) is listed and makes the script exit 1.

Usage: scripts/robustness.py [JOB] [--end S] [--timeout S] [--values a,b,...]
(after a build; JOB defaults to the hemisphere scene, about 15 minutes;
the variants are written to a temporary folder, so a job that names files
by relative paths needs them made absolute first).
"""
import argparse
import copy
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXE = os.environ.get("THERMOSTAMP_EXE", os.path.join(ROOT, "build", "bin", "thermostamp"))


def leaves(node, path=()):
    """Paths of every number in a JSON document."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield from leaves(v, path + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from leaves(v, path + (i,))
    elif isinstance(node, (int, float)) and not isinstance(node, bool):
        yield path


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("job", nargs="?", default=os.path.join(ROOT, "share", "jobs", "hemisphere_ud_2ply.json"))
    ap.add_argument("--end", type=float, default=0.005, help="time.end of every variant (s)")
    ap.add_argument("--timeout", type=float, default=120, help="wall time allowed per variant (s)")
    ap.add_argument("--values", default="0,-1,1e30,1e-30,3.5")
    args = ap.parse_args()
    base = json.load(open(args.job))
    base["time"]["end"] = args.end
    output = base.setdefault("output", {})
    output["interval"] = args.end / 2
    for p in output.get("probes", []):
        p["interval"] = args.end / 2
    values = [float(v) for v in args.values.split(",")]
    counts, bad = {}, []
    with tempfile.TemporaryDirectory() as d:
        job_path = os.path.join(d, "job.json")
        for path in leaves(base):
            if path[0] == "time":
                continue
            for v in values:
                job = copy.deepcopy(base)
                node = job
                for k in path[:-1]:
                    node = node[k]
                node[path[-1]] = v
                json.dump(job, open(job_path, "w"))
                cmd = [EXE, "run", job_path, "--out", os.path.join(d, "out"), "--quiet", "--threads", "1"]
                try:
                    r = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
                    errors = [l for l in r.stderr.splitlines() if l.startswith("error:")]
                    code, last = r.returncode, (errors or r.stderr.strip().splitlines() or [""])[-1]
                except subprocess.TimeoutExpired:
                    code, last = "timeout", ""
                counts[code] = counts.get(code, 0) + 1
                where = "/" + "/".join(str(k) for k in path)
                if code == 3:
                    print("stopped %s = %g: %s" % (where, v, last[:200]), flush=True)
                if code not in (0, 2, 3):
                    bad.append((where, v, code, last))
                    print("FAIL %s = %g: %s %s" % (where, v, code, last[:200]), flush=True)
    print("variants by exit status: %s" % ", ".join("%s: %d" % (k, n) for k, n in sorted(counts.items(), key=str)))
    if bad:
        print("%d variant(s) crashed, hung or ended otherwise" % len(bad))
        sys.exit(1)


if __name__ == "__main__":
    main()
