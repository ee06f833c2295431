"""What the small-deflection bending studies share: a flat rectangle meshed
like the rectangle generator (alternating diagonals, or crossed with a
centre node per cell), its edges, and the gradient of each triangle's
linear interpolant."""
import numpy as np


def flat_mesh(nx, ny, lx, ly, crossed):
    """X (nodes x 2), T (triangles x 3), idx[(i, j)] (grid nodes), emap
    (edge -> [(element, k)], k the edge's opposite corner), G (per triangle,
    the 2 x 3 map from its node values to the gradient) and A (areas)."""
    nodes, idx, tris = [], {}, []
    for j in range(ny + 1):
        for i in range(nx + 1):
            idx[(i, j)] = len(nodes)
            nodes.append((i * lx / nx, j * ly / ny))
    for j in range(ny):
        for i in range(nx):
            a, b, c, d = idx[(i, j)], idx[(i + 1, j)], idx[(i + 1, j + 1)], idx[(i, j + 1)]
            if crossed:
                m = len(nodes)
                nodes.append(((i + .5) * lx / nx, (j + .5) * ly / ny))
                tris += [(a, b, m), (b, c, m), (c, d, m), (d, a, m)]
            elif (i + j) % 2 == 0:
                tris += [(a, b, c), (a, c, d)]
            else:
                tris += [(a, b, d), (b, c, d)]
    X, T = np.array(nodes), np.array(tris)
    emap = {}
    for e, t in enumerate(T):
        for k in range(3):
            emap.setdefault(frozenset((t[(k + 1) % 3], t[(k + 2) % 3])), []).append((e, k))
    G, A = [], []
    for t in T:
        P = X[list(t)]
        M = np.array([[1, P[0, 0], P[0, 1]], [1, P[1, 0], P[1, 1]], [1, P[2, 0], P[2, 1]]])
        G.append(np.linalg.inv(M)[1:, :])
        A.append(0.5 * abs(np.linalg.det(M)))
    return X, T, idx, emap, G, A
