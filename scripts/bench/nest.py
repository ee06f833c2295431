#!/usr/bin/env python3
"""Roll layout benchmark: the time `thermostamp blank --roll` takes to lay
a pattern on a roll (scripts/bench/nest_roll.cpp, linked to the Release
build's core library): a disc and an ellipse on a roll 0.6 m wide, copies
alike, pairs tried, and batches of 10, 1 000 and 10 000 patterns of the
pairs' layout (`--parts`); one thread, best of 3. Prints a Markdown table.

Usage: scripts/bench/nest.py
(after a Release build: cmake -S . -B build -DCMAKE_BUILD_TYPE=Release).
"""
import os
import subprocess

from blank import build  # compiles a benchmark against the core library


def main():
    exe = build("nest_roll")
    out = subprocess.run([exe], env=dict(os.environ, OMP_NUM_THREADS="1"), check=True, capture_output=True,
                         text=True).stdout.splitlines()
    print("| pattern | gap (mm) | alike (s) | pairs tried (s) | batch of 10 (ms) | of 1 000 (ms) | of 10 000 (ms) "
          "| batches' lengths (m) |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for line in out:
        f = line.split()
        ms = " | ".join(f"{1000 * float(x):.3f}" for x in f[4:7])
        print(f"| {f[0]} | {1000 * float(f[1]):g} | {f[2]} | {f[3]} | {ms} | {f[7]} / {f[8]} / {f[9]} |")


if __name__ == "__main__":
    main()
