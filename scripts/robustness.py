#!/usr/bin/env python3
"""Robustness sweep of a job, each variant run for a short time:
- numbers: every number set in turn to extreme values (0, -1, 1e30,
  1e-30, 3.5 by default);
- structure (--structure): every key and array entry removed in turn, and
  every value replaced in turn by a string, null, an empty array and an
  empty object.
Each variant must end with exit 0 (ran), 2 (refused as input, before
running, with one line naming a JSON path) or 3 (stopped with a message),
within the timeout. Anything else (a crash, a signal, a hang, an input
error without a JSON path) is listed and makes the script exit 1.

Usage: scripts/robustness.py [JOB] [--end S] [--timeout S] [--values a,b,...] [--structure] [--threads N]
(after a build; JOB defaults to the hemisphere scene: about 15 minutes for
the numbers, a few for the structure, whose variants are mostly refused
at once; the variants are written
to a temporary folder, so a job that names files by relative paths needs
them made absolute first).
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


def paths(node, path=()):
    """(path, value) of every value below the document's root."""
    if isinstance(node, dict):
        items = node.items()
    elif isinstance(node, list):
        items = enumerate(node)
    else:
        return
    for k, v in items:
        yield path + (k,), v
        yield from paths(v, path + (k,))


def is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def variants(base, values, structure):
    """(description, job) pairs; time.end and the output times are kept."""
    for path, value in list(paths(base)):
        if path[0] == "time":
            continue
        where = "/" + "/".join(str(k) for k in path)
        edits = []
        if is_number(value):
            edits += [("= %g" % v, v) for v in values]
        if structure:
            edits += [("removed", None)] + [("= %s" % json.dumps(v), v) for v in ("x", None, [], {}) if v != value]
        for what, v in edits:
            job = copy.deepcopy(base)
            node = job
            for k in path[:-1]:
                node = node[k]
            if what == "removed":
                del node[path[-1]]
            else:
                node[path[-1]] = copy.deepcopy(v)
            yield "%s %s" % (where, what), job


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("job", nargs="?", default=os.path.join(ROOT, "share", "jobs", "hemisphere_ud_2ply.json"))
    ap.add_argument("--end", type=float, default=0.005, help="time.end of every variant (s)")
    ap.add_argument("--timeout", type=float, default=120, help="wall time allowed per variant (s)")
    ap.add_argument("--values", default="0,-1,1e30,1e-30,3.5")
    ap.add_argument("--structure", action="store_true", help="also remove keys and change the types of values")
    ap.add_argument("--threads", type=int, default=1, help="threads of every run")
    args = ap.parse_args()
    base = json.load(open(args.job))
    base["time"]["end"] = args.end
    output = base.setdefault("output", {})
    output["interval"] = args.end / 2
    for p in output.get("probes", []):
        p["interval"] = args.end / 2
    values = [float(v) for v in args.values.split(",")] if args.values else []
    counts, bad = {}, []
    with tempfile.TemporaryDirectory() as d:
        job_path = os.path.join(d, "job.json")
        for what, job in variants(base, values, args.structure):
            json.dump(job, open(job_path, "w"))
            cmd = [EXE, "run", job_path, "--out", os.path.join(d, "out"), "--quiet", "--threads", str(args.threads)]
            try:
                r = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
                errors = [l for l in r.stderr.splitlines() if l.startswith("error:")]
                code, last = r.returncode, (errors or r.stderr.strip().splitlines() or [""])[-1]
            except subprocess.TimeoutExpired:
                code, last = "timeout", ""
            counts[code] = counts.get(code, 0) + 1
            if code == 3:
                print("stopped %s: %s" % (what, last[:200]), flush=True)
            # An input error names the JSON path it is about.
            unplaced = code == 2 and not last.startswith("error: /")
            if code not in (0, 2, 3) or unplaced:
                bad.append((what, code, last))
                print("FAIL %s: %s %s" % (what, code, last[:200]), flush=True)
    print("variants by exit status: %s" % ", ".join("%s: %d" % (k, n) for k, n in sorted(counts.items(), key=str)))
    if bad:
        print("%d variant(s) crashed, hung, or were refused without a JSON path" % len(bad))
        sys.exit(1)


if __name__ == "__main__":
    main()
