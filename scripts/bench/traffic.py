#!/usr/bin/env python3
"""Memory traffic and instructions per element-cycle of the mechanics
benchmark's plate, by function: two runs under cachegrind (valgrind), of
SHORT and LONG cycles, and their difference divided by (elements x
(LONG - SHORT)), so that the set-up drops out. The last-level cache is
simulated with --cache-bytes (default: the processor's per-core cache, as
`getconf LEVEL2_CACHE_SIZE` reports it), so "bytes" are the lines that
miss a cache of that size (read misses and write allocations; write-backs
of dirty lines come on top and are not counted).

Unlike wall times, these figures do not depend on what else the machine
is doing: two builds compare to the byte and the instruction. They do not
count what an instruction costs (a division, a gather, a mispredicted
branch), so check a change that trades instructions for bytes with timed
runs as well (compare.py).

Usage: scripts/bench/traffic.py [--n 71] [--short 50] [--long 250]
       [--cache-bytes B] [--top 20] [--exe build/bin/thermostamp]
(n = 71 gives the 10k plate; valgrind runs about 50 times slower; it is
the Debian package valgrind, which scripts/setup does not install.)
"""
import argparse
import collections
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mechanics  # noqa: E402


def cachegrind(exe, job, cache_bytes, d, tag):
    path = os.path.join(d, tag + ".json")
    json.dump(job, open(path, "w"))
    out = os.path.join(d, tag + ".cg")
    # The element plans its memory for the simulated cache (under valgrind
    # the system reports another size).
    env = dict(os.environ, THERMOSTAMP_CACHE_BYTES=str(cache_bytes))
    subprocess.run(["valgrind", "--tool=cachegrind", "--cache-sim=yes", "--LL=%d,16,64" % cache_bytes,
                    "--cachegrind-out-file=" + out, exe, "run", path, "--out", os.path.join(d, tag),
                    "--threads", "1", "--quiet"], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                   env=env)
    events, per_fn, fn = None, collections.Counter(), None
    for line in open(out):
        if line.startswith("events:"):
            events = line.split()[1:]
        elif line.startswith("fn="):
            fn = line[3:].strip()
        elif line[:1].isdigit():
            for k, v in zip(events, map(int, line.split()[1:])):
                per_fn[(fn, k)] += v
    return per_fn


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=71)
    ap.add_argument("--short", type=int, default=50)
    ap.add_argument("--long", type=int, default=250)
    ap.add_argument("--cache-bytes", type=int, default=0)
    ap.add_argument("--top", type=int, default=20)
    ap.add_argument("--exe", default=mechanics.EXE)
    args = ap.parse_args()
    cache = args.cache_bytes
    if cache <= 0:
        try:
            cache = int(subprocess.run(["getconf", "LEVEL2_CACHE_SIZE"], capture_output=True, text=True).stdout)
        except ValueError:
            cache = 0
        cache = cache if cache > 0 else 1 << 20
    with tempfile.TemporaryDirectory() as d:
        a = cachegrind(args.exe, mechanics.job(args.n, args.short), cache, d, "short")
        b = cachegrind(args.exe, mechanics.job(args.n, args.long), cache, d, "long")
    scale = 1.0 / (2 * args.n * args.n * (args.long - args.short))
    rows = []
    for fn in {k[0] for k in b}:
        rd = (b[(fn, "DLmr")] - a[(fn, "DLmr")]) * 64 * scale
        wr = (b[(fn, "DLmw")] - a[(fn, "DLmw")]) * 64 * scale
        ir = (b[(fn, "Ir")] - a[(fn, "Ir")]) * scale
        rows.append((rd + wr, rd, wr, ir, fn))
    rows.sort(reverse=True)
    total = [sum(r[i] for r in rows) for i in range(4)]
    print("%d elements, cycles %d - %d, simulated cache %d bytes" % (2 * args.n * args.n, args.long, args.short, cache))
    print("\n| function | bytes | read | write | instructions |\n|---|---|---|---|---|")
    print("| all | %.0f | %.0f | %.0f | %.0f |" % tuple(total))
    for r in rows[:args.top]:
        name = r[4].replace("(anonymous namespace)::", "").split("(")[0]
        print("| `%s` | %.1f | %.1f | %.1f | %.1f |" % (name, r[0], r[1], r[2], r[3]))


if __name__ == "__main__":
    main()
