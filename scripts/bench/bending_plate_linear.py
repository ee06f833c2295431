#!/usr/bin/env python3
"""Small-deflection statics of plates with the rotation-free triangle's
curvature operators (triangle_patch.Plate: `hinge`, `morley` = shell_rf_t3
0.4, `exact`), solved directly (no time stepping). With `hinge` and
`morley` it reproduces the explicit runs' deflections (scripts/bench/
calculix_plate.py) to the digit. Isotropic plate, D = 1, nu = 0.

Cases:
  corner   the 100 mm square clamped along x = 0, a corner force of 0.01 N;
           against CalculiX S8R 40 x 40 (converged)
  clamped  the unit square clamped all round under a uniform load; centre
           deflection against 0.0012653 q a^4 / D (Timoshenko & Woinowsky-
           Krieger, table 35; independent of nu for a clamped plate)

Usage: scripts/bench/bending_plate_linear.py corner|clamped alternating|crossed hinge|morley|exact N [N ...]
(needs numpy)
"""
import sys

import numpy as np

from triangle_patch import Plate

case, pattern, mode = sys.argv[1:4]
D = np.diag([1.0, 1.0, 0.5])   # M = D (k11, k22, 2 k12): nu = 0, twist rigidity D (1 - nu) / 2
for n in [int(a) for a in sys.argv[4:]]:
    if case == "corner":
        L, F = 0.1, 0.01
        P = Plate(n, n, L, L, pattern == "crossed", lambda x: x[0] < 1e-12)
        held = [i for i in range(P.N) if P.X[i, 0] < 1e-12]
        f = np.zeros(P.N)
        f[P.idx[(n, n)]] = F
        ref = {"loaded corner": (4.514869e-05, (n, n)), "free corner": (2.508407e-05, (n, 0)),
               "tip middle": (3.237018e-05, (n, n // 2)), "centre": (1.012974e-05, (n // 2, n // 2))}
    else:
        P = Plate(n, n, 1.0, 1.0, pattern == "crossed", lambda x: True)
        held = [i for i in range(P.N) if min(P.X[i, 0], P.X[i, 1], 1 - P.X[i, 0], 1 - P.X[i, 1]) < 1e-12]
        f = np.zeros(P.N)
        for e in range(P.E):
            f[list(P.T[e])] += P.A[e] / 3
        ref = {"centre": (0.0012653, (n // 2, n // 2))}
    H = P.stiffness(P.operator(mode, D), D)
    free = [i for i in range(P.N) if i not in set(held)]
    w = np.zeros(P.N)
    w[free] = np.linalg.solve(H[np.ix_(free, free)], f[free])
    print("%-7s %-8s %-11s %3d x %-3d: " % (case, mode, pattern, n, n) +
          "  ".join("%s %+.2f %%" % (k, 100 * (w[P.idx[ij]] / v - 1)) for k, (v, ij) in ref.items()))
