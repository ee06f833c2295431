#!/usr/bin/env python3
"""Small-deflection statics of the corner-loaded plate of
scripts/bench/calculix_plate.py with the rotation-free triangle's curvature
operators, solved directly (no time stepping): `hinge` (the element's
formula; it reproduces the explicit runs' deflections to the digit),
`exact_inner` (the map from the hinge angles made exact for every constant
curvature in the elements with three neighbours), `exact_all` (also in the
elements on a free edge, whose missing hinge row is replaced by M_nn = 0).
Prints the deflections against CalculiX S8R (40 x 40, converged).

Usage: scripts/bench/bending_plate_linear.py N alternating|crossed MODE [twist_ratio]  (needs numpy)
"""
import sys

import numpy as np

from triangle_patch import flat_mesh
# Linear small-deflection plate with the rotation-free triangle's curvature operators.
# Square L x L clamped at x = 0, corner force at (L, L); D = 1, nu = 0, twist as given.
n = int(sys.argv[1]); pattern = sys.argv[2]; mode = sys.argv[3]; twist = float(sys.argv[4]) if len(sys.argv) > 4 else 1.0
L = 0.1; F = 0.01
X, T, idx, emap, G, A = flat_mesh(n, n, L, L, pattern == 'crossed')
N = len(X); E = len(T)
def edge_info(e, k):
    t = T[e]; p, q = t[(k+1)%3], t[(k+2)%3]
    d = X[q] - X[p]; nu = np.array([d[1], -d[0]]) / np.linalg.norm(d)
    if np.dot(nu, X[t[k]] - X[p]) > 0: nu = -nu
    return p, q, nu, np.linalg.norm(d)
def theta_row(e, k):
    """hinge angle (slope jump) row; clamped ghost: 2 x (0 - g_e . nu); free: None"""
    t = T[e]; p, q, nu, l = edge_info(e, k)
    lst = emap[frozenset((p,q))]
    row = np.zeros(N)
    if len(lst) == 2:
        (e2, k2) = [x for x in lst if x[0] != e][0]
        row[list(T[e2])] += G[e2].T @ nu
        row[list(t)] -= G[e].T @ nu
        return row, 'inner'
    if X[p,0] < 1e-12 and X[q,0] < 1e-12:   # clamped edge: ghost mirror, theta = 2 x rotation
        row[list(t)] -= 2 * G[e].T @ nu
        return row, 'clamp'
    return row, 'free'   # free edge: theta = 0
W = np.diag([1.0, 1.0, 2.0 * twist])
H = np.zeros((N, N))
for e in range(E):
    rows = [theta_row(e, k) for k in range(3)]
    J = np.array([r[0] for r in rows])
    kinds = [r[1] for r in rows]
    hinge = np.array([[l/(2*A[e])*nu[0]**2, l/(2*A[e])*nu[1]**2, l/(2*A[e])*nu[0]*nu[1]] for (p,q,nu,l) in [edge_info(e,k) for k in range(3)]]).T
    use_exact = mode != 'hinge' and (all(k != 'free' for k in kinds) if mode == 'exact_inner' else True)
    if use_exact:
        cen = X[list(T[e])].mean(axis=0); Xc = X - cen
        B = np.zeros((3, 3))
        for jj, w in enumerate([0.5*Xc[:,0]**2, 0.5*Xc[:,1]**2, Xc[:,0]*Xc[:,1]]):
            B[:, jj] = J @ w
        if mode == 'exact_all' and 'free' in kinds:
            # free edge: replace its (zero) hinge row by M_nn = 0 (nu = 0 isotropic: K_nn = 0)
            Bm = B.copy(); Jm = J.copy()
            for k in range(3):
                if kinds[k] == 'free':
                    p, q, nu, l = edge_info(e, k)
                    Bm[k, :] = [nu[0]**2, nu[1]**2, 2*nu[0]*nu[1]]   # K_nn = K11 n1^2 + K22 n2^2 + 2 K12 n1 n2
                    Jm[k, :] = 0.0
            Kop = np.linalg.solve(Bm, Jm)
        else:
            Kop = np.linalg.solve(B, J)
    else:
        Kop = hinge @ J
    H += A[e] * Kop.T @ W @ Kop
fixed = [i for i in range(N) if X[i,0] < 1e-12]
free = [i for i in range(N) if i not in fixed]
f = np.zeros(N); f[idx[(n, n)]] = F
w = np.zeros(N); w[free] = np.linalg.solve(H[np.ix_(free, free)], f[free])
ref = {"loaded": 4.514869e-05, "free corner": 2.508407e-05, "tip middle": 3.237018e-05, "centre": 1.012974e-05}
pts = {"loaded": idx[(n, n)], "free corner": idx[(n, 0)], "tip middle": idx[(n, n//2)], "centre": idx[(n//2, n//2)]}
print("%-12s %-11s %3d x %-3d twist %.1f: " % (mode, pattern, n, n, twist) + "  ".join("%s %+.1f%%" % (k, 100*(w[v]/ref[k]-1)) for k, v in pts.items()))
