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

The job itself must run (exit 0) for --end S first; otherwise the script
says why and exits 2, since every variant would be refused for the same
reason.

Usage: scripts/robustness.py [JOB] [--end S] [--timeout S] [--values a,b,...] [--structure] [--threads N]
(after a build; JOB defaults to the hemisphere scene: about 15 minutes for
the numbers, a few for the structure, whose variants are mostly refused
at once). The variants are written to a temporary folder: every string of
the job that names a file or folder relative to the job's own folder (a
mesh, a material card, a plugin path) is made absolute first.
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


def absolute_paths(node, folder):
    """Every string below node that names an existing file or folder
    relative to folder, made absolute (in place)."""
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for k, v in items:
        if isinstance(v, str) and v and not os.path.isabs(v) and os.path.exists(os.path.join(folder, v)):
            node[k] = os.path.abspath(os.path.join(folder, v))
        else:
            absolute_paths(v, folder)


def run(job, d, threads, timeout):
    """Runs job from folder d: (exit status or "timeout", the last error line)."""
    job_path = os.path.join(d, "job.json")
    json.dump(job, open(job_path, "w"))
    cmd = [EXE, "run", job_path, "--out", os.path.join(d, "out"), "--quiet", "--threads", str(threads)]
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return "timeout", ""
    errors = [l for l in r.stderr.splitlines() if l.startswith("error:")]
    return r.returncode, (errors or r.stderr.strip().splitlines() or [""])[-1]


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
    absolute_paths(base, os.path.dirname(os.path.abspath(args.job)))
    base["time"]["end"] = args.end
    output = base.setdefault("output", {})
    output["interval"] = args.end / 2
    for p in output.get("probes", []):
        p["interval"] = args.end / 2
    values = [float(v) for v in args.values.split(",")] if args.values else []
    counts, bad = {}, []
    with tempfile.TemporaryDirectory() as d:
        code, last = run(base, d, args.threads, args.timeout)
        if code != 0:
            print("the job itself does not run to %g s (exit status %s): %s" % (args.end, code, last[:300]))
            sys.exit(2)
        for what, job in variants(base, values, args.structure):
            code, last = run(job, d, args.threads, args.timeout)
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
