#!/usr/bin/env python3
"""Small-deflection study of the rotation-free triangle's curvature operator
(docs/verification.md, "Bending in two dimensions"): on a unit square meshed
like the rectangle generator (alternating diagonals, or crossed with `c`),
the bending energy of nodal deflection fields with the hinge formula
K = sum_k l_k / (2 A) theta_k nu_k (x) nu_k and with the map from the hinge
angles made exact for every constant curvature (the inverse of the 3 x 3
map from K to the hinge angles of the element's 6-node patch), against the
integral of D/2 (k11^2 + k22^2 + 2 k12^2) over the same elements (D = 1,
nu = 0). Only elements with three neighbours count. Also the lowest
eigenvalues of the bending stiffness with the boundary nodes held.

Usage: scripts/bench/bending_operator.py NX NY [c]   (needs numpy)
"""
import sys

import numpy as np

from triangle_patch import flat_mesh
nx, ny = int(sys.argv[1]), int(sys.argv[2]); crossed = len(sys.argv) > 3 and sys.argv[3] == 'c'
Lx, Ly = 1.0, 1.0
X, T, idx, emap, G, A = flat_mesh(nx, ny, Lx, Ly, crossed)
N = len(X); E = len(T)
# hinge angle rows: theta_k(e) = (g_nb - g_e) . nu_k  (nu outward of e)
def theta_row(e, k):
    t = T[e]; p, q = t[(k+1)%3], t[(k+2)%3]
    lst = emap[frozenset((p,q))]
    if len(lst) < 2: return None
    (e2, k2) = [x for x in lst if x[0] != e][0]
    d = X[q] - X[p]; nu = np.array([d[1], -d[0]]) / np.linalg.norm(d)
    c = X[t[k]]
    if np.dot(nu, c - X[p]) > 0: nu = -nu   # outward (away from the opposite vertex)
    row = np.zeros(N)
    row[list(T[e2])] += G[e2].T @ nu
    row[list(t)] -= G[e].T @ nu
    return row, nu, np.linalg.norm(d)
def assemble(mode):
    H = np.zeros((N, N))
    for e in range(E):
        rows = [theta_row(e, k) for k in range(3)]
        if any(r is None for r in rows): continue  # boundary elements left out
        J = np.array([r[0] for r in rows])
        if mode == 'hinge':
            Gm = np.array([[r[2]/(2*A[e]) * r[1][0]**2, r[2]/(2*A[e]) * r[1][1]**2, r[2]/(2*A[e]) * r[1][0]*r[1][1]] for r in rows]).T  # 3 (K) x 3 (theta)
        else:
            # B: theta for unit curvatures w = 1/2 X^T K X (centroid origin)
            cen = X[list(T[e])].mean(axis=0)
            B = np.zeros((3,3))
            for jj in range(3):
                Xc = X - cen
                w = [0.5*Xc[:,0]**2, 0.5*Xc[:,1]**2, Xc[:,0]*Xc[:,1]][jj]
                B[:, jj] = J @ w
            Gm = np.linalg.inv(B)
        Kop = Gm @ J   # 3 x N
        W = np.diag([1.0, 1.0, 2.0])  # energy 1/2 (k11^2 + k22^2 + 2 k12^2), D = 1, nu = 0
        H += A[e] * Kop.T @ W @ Kop
    return H
bnd = [i for i in range(N) if X[i,0] < 1e-9 or X[i,0] > Lx-1e-9 or X[i,1] < 1e-9 or X[i,1] > Ly-1e-9]
free = [i for i in range(N) if i not in bnd]
for mode in ('hinge', 'exact'):
    H = assemble(mode)[np.ix_(free, free)]
    ev, vec = np.linalg.eigh(H)
    # smoothness of the lowest mode: ratio of its energy to that of the smooth sin mode
    h2 = (Lx/nx)*(Ly/ny)/(2 if crossed else 1)
    print(mode, "lowest eigenvalue per node area:", np.round(ev[:3]/h2, 1))
    v = vec[:, 0]; x = X[free]
    print("   lowest mode correlation with sin(pi x) sin(pi y):", abs(np.dot(v, np.sin(np.pi*x[:,0])*np.sin(np.pi*x[:,1]))) / np.linalg.norm(np.sin(np.pi*x[:,0])*np.sin(np.pi*x[:,1])))
# clamped-plate continuum reference (simply supported, Dirichlet w only approximates): lowest biharmonic SS eigenvalue 4 pi^4 = 389.6 per unit area...
print("simply supported plate, first eigenvalue of D nabla^4 (D = 1, unit square): %.1f" % (4*np.pi**4))
# energy of smooth fields with both operators vs the integral over the elements used
def energy_check(wfun, d2):
    for mode in ('hinge', 'exact'):
        H = assemble(mode)
        v = wfun(X[:,0], X[:,1])
        Eh = 0.5 * v @ H @ v
        # exact over the same elements (centroid rule)
        Ee = 0.0
        for e in range(E):
            rows = [theta_row(e, k) for k in range(3)]
            if any(r is None for r in rows): continue
            c = X[list(T[e])].mean(axis=0)
            kxx, kyy, kxy = d2(c[0], c[1])
            Ee += A[e] * 0.5 * (kxx**2 + kyy**2 + 2*kxy**2)
        print("  %s: discrete %.4f, integral %.4f, ratio %.3f" % (mode, Eh, Ee, Eh/Ee))
print("w = sin(pi x) sin(pi y)")
energy_check(lambda x, y: np.sin(np.pi*x)*np.sin(np.pi*y), lambda x, y: (-np.pi**2*np.sin(np.pi*x)*np.sin(np.pi*y), -np.pi**2*np.sin(np.pi*x)*np.sin(np.pi*y), np.pi**2*np.cos(np.pi*x)*np.cos(np.pi*y)))
print("w = x y (pure twist)")
energy_check(lambda x, y: x*y, lambda x, y: (0.0, 0.0, 1.0))
print("w = x^2/2")
energy_check(lambda x, y: 0.5*x*x, lambda x, y: (1.0, 0.0, 0.0))
print("w = sin(pi x)")
energy_check(lambda x, y: np.sin(np.pi*x), lambda x, y: (-np.pi**2*np.sin(np.pi*x), 0.0, 0.0))
