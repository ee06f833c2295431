#!/usr/bin/env python3
"""Cut pattern benchmark: the time `thermostamp blank` takes to find a
ply's pattern (scripts/bench/blank_patterns.cpp, linked to the Release
build's core library): a plate of 0.3 m in N x N crossed cells, trimmed by
a cylinder, by a polygon of V vertices on the same circle, and by that
polygon with a plane; one thread, best of 3. Prints a Markdown table.

Usage: scripts/bench/blank.py [--cells N] [--vertices V ...]
(after a Release build: cmake -S . -B build -DCMAKE_BUILD_TYPE=Release).
"""
import argparse
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def build(name="blank_patterns"):
    """Compiles scripts/bench/NAME.cpp against the Release build's core
    library into build/bench/NAME; returns its path."""
    src = os.path.join(ROOT, "scripts", "bench", name + ".cpp")
    lib = os.path.join(ROOT, "build", "core", "libthermostamp_core.a")
    exe = os.path.join(ROOT, "build", "bench", name)
    if not os.path.exists(lib):
        sys.exit("no build/core/libthermostamp_core.a: build first (cmake -S . -B build -DCMAKE_BUILD_TYPE=Release)")
    os.makedirs(os.path.dirname(exe), exist_ok=True)
    subprocess.run([os.environ.get("CXX", "g++"), "-O3", "-march=native", "-fopenmp", "-std=c++20",
                    "-I" + os.path.join(ROOT, "core"), src, lib, "-lhdf5_serial", "-lspdlog", "-lfmt",
                    "-o", exe], check=True)
    return exe


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=224)
    ap.add_argument("--vertices", type=int, nargs="+", default=[1000, 10000])
    ap.add_argument("--reps", type=int, default=1, help="ignored (each case is timed 3 times)")
    args = ap.parse_args()
    exe = build()
    env = dict(os.environ, OMP_NUM_THREADS="1")
    print("| polygon vertices | trim | time (s) | pattern area (m^2) |")
    print("| --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as tmp:
        for v in args.vertices:
            out = subprocess.run([exe, str(args.cells), str(v), os.path.join(tmp, "circle.csv")], env=env,
                                 check=True, capture_output=True, text=True).stdout.splitlines()
            print(f"<!-- {out[0]} -->")
            for line in out[1:]:
                name, seconds, _, _, area, _ = line.split()
                print(f"| {v} | {name} | {float(seconds):.3f} | {area} |")


if __name__ == "__main__":
    main()
