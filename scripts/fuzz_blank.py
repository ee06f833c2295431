#!/usr/bin/env python3
"""Fuzzing of `thermostamp blank`'s cut (scripts/fuzz/*.cpp, linked to
the core library of a build): random meshes and trims (every outline must
close, its area the pattern's, a trim given twice the pattern once),
mutated DXF outlines (read and cut, or refused in one line), polygons
moved by a margin (against the distance to the polygon), random patterns
nested on a roll (copies apart by the gap, by their exact distances), and the unit
test of trims through the mesh's nodes and along its lines (areas against
clipping in the blank) with more cases. Exit status 1 where any case fails; the failing case's number
reruns it alone (the programs' last argument).

Usage: scripts/fuzz_blank.py [--cases N] [--seeds S ...] [--sanitize]
(after a Release build with its tests, or with --sanitize after
scripts/sanitize, which links against build-sanitize/ with ASan and UBSan). Default: 20 000 cases
of each kind for seed 1 (of random patterns on a roll a tenth as many),
about 5 minutes (the margins' grid checks 2 of them; sanitized much
longer).
"""
import argparse
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SAN = ["-O1", "-g", "-fno-omit-frame-pointer", "-fsanitize=address,undefined", "-fno-sanitize-recover=undefined"]


def build(name, sanitize):
    tree = "build-sanitize" if sanitize else "build"
    lib = os.path.join(ROOT, tree, "core", "libthermostamp_core.a")
    if not os.path.exists(lib):
        sys.exit(f"no {tree}/core/libthermostamp_core.a: build first")
    exe = os.path.join(ROOT, tree, "fuzz", name)
    os.makedirs(os.path.dirname(exe), exist_ok=True)
    flags = SAN if sanitize else ["-O2"]
    src = os.path.join(ROOT, "scripts", "fuzz", name + ".cpp")
    subprocess.run([os.environ.get("CXX", "g++")] + flags +
                   ["-fopenmp", "-std=c++20", "-I" + os.path.join(ROOT, "core"), src, lib,
                    "-lhdf5_serial", "-lspdlog", "-lfmt", "-o", exe], check=True)
    return exe


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=20000)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1])
    ap.add_argument("--sanitize", action="store_true")
    args = ap.parse_args()
    env = dict(os.environ, ASAN_OPTIONS="detect_leaks=0:abort_on_error=1", UBSAN_OPTIONS="print_stacktrace=1")
    failed = False
    # Trims along the mesh: the unit test's cases, more of them.
    tests = os.path.join(ROOT, "build-sanitize" if args.sanitize else "build", "bin", "unit_tests")
    for seed in args.seeds:
        r = subprocess.run([tests, "--gtest_filter=Blank.TrimsThroughNodesAndAlongTheMeshLines", "--gtest_brief=1"],
                           env=dict(env, THERMOSTAMP_BLANK_CASES=str(args.cases), THERMOSTAMP_BLANK_SEED=str(seed)),
                           capture_output=True, text=True)
        print(f"aligned seed {seed}: {args.cases} cases, " + ("passed" if r.returncode == 0 else "FAILED"))
        if r.returncode != 0:
            failed = True
            print(r.stdout[-4000:] + r.stderr[-2000:], end="")
    for name in ("blank_random", "blank_dxf", "blank_margin", "nest_random"):
        exe = build(name, args.sanitize)
        for seed in (args.seeds if name != "blank_dxf" else [None]):
            cases = max(1, args.cases // 10) if name == "nest_random" else args.cases  # its cases cost ten times
            cmd = [exe, str(cases)] + ([] if seed is None else [str(seed)])
            r = subprocess.run(cmd, env=env, capture_output=True, text=True)
            last = r.stdout.strip().splitlines()[-1] if r.stdout.strip() else "(no output)"
            print(f"{name}{'' if seed is None else ' seed ' + str(seed)}: {last}")
            if r.returncode != 0:
                failed = True
                print(r.stdout + r.stderr, end="")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
