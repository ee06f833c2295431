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


class Plate:
    """Small-deflection bending operators of the rotation-free triangle on a
    flat_mesh; clamped_fn(point) tells the held boundary edges (both nodes),
    the other boundary edges are free. operator(mode, D) gives per element
    (area, 3 x N map from nodal deflections to (k11, k22, k12)):
    'hinge': K = sum l / (2 A) theta nu (x) nu (shell_rf_t3 before 0.4);
    'exact': the quadratic of each element's 6-node patch (its Hessian), the
    hinge formula where an edge is free (tried, left out: not convergent);
    'morley': shell_rf_t3 0.4, K = sum l / A s nu (x) nu with the mid-edge
    slope s shared by the two elements of an edge (the mean of their
    quadratics' slopes, one of them where the other has none), zero at a
    clamped edge, M_nn = 0 at a free edge (D: 3 x 3, M = D (k11, k22, 2 k12))."""
    def __init__(s,nx,ny,lx,ly,crossed,clamped_fn):
        s.X,s.T,s.idx,s.emap,s.G,s.A=flat_mesh(nx,ny,lx,ly,crossed)
        s.N=len(s.X);s.E=len(s.T);s.clamped_fn=clamped_fn
    def edge_info(s,e,k):
        X,T=s.X,s.T;t=T[e];p,q=t[(k+1)%3],t[(k+2)%3]
        d=X[q]-X[p];nu=np.array([d[1],-d[0]])/np.linalg.norm(d)
        if np.dot(nu,X[t[k]]-X[p])>0: nu=-nu
        return p,q,nu,np.linalg.norm(d)
    def kind(s,e,k):
        p,q,nu,l=s.edge_info(e,k)
        if len(s.emap[frozenset((p,q))])==2: return 'inner'
        return 'clamp' if s.clamped_fn(s.X[p]) and s.clamped_fn(s.X[q]) else 'free'
    def theta_row(s,e,k):
        t=s.T[e];p,q,nu,l=s.edge_info(e,k);row=np.zeros(s.N);kd=s.kind(e,k)
        if kd=='inner':
            (e2,k2)=[x for x in s.emap[frozenset((p,q))] if x[0]!=e][0]
            row[list(s.T[e2])]+=s.G[e2].T@nu
            row[list(s.T[e])]-=s.G[e].T@nu
        elif kd=='clamp': row[list(t)]-=2*s.G[e].T@nu
        return row
    def hessian_fit(s,e):
        """3 x N: Hessian (k11,k22,k12) of the quadratic of e's 6-node patch (clamped: ghost); None if a free edge"""
        if any(s.kind(e,k)=='free' for k in range(3)): return None
        J=np.array([s.theta_row(e,k) for k in range(3)])
        cen=s.X[list(s.T[e])].mean(axis=0);Xc=s.X-cen;B=np.zeros((3,3))
        for jj,w in enumerate([0.5*Xc[:,0]**2,0.5*Xc[:,1]**2,Xc[:,0]*Xc[:,1]]): B[:,jj]=J@w
        return np.linalg.solve(B,J)
    def rel_slope_own(s,e,k,Hk):
        """outward normal slope at mid-edge k relative to e's plane, of e's quadratic with Hessian rows Hk"""
        t=s.T[e];p,q,nu,l=s.edge_info(e,k)
        # relative quadratic r = 1/2 x.Kx + linear + c vanishing at 3 vertices; slope at midpoint
        P=s.X[list(t)];M=np.column_stack([np.ones(3),P])
        m=0.5*(s.X[p]+s.X[q])
        # r(x)=0.5 x^T K x - L(x), L the linear interpolant of 0.5 x^T K x; grad r(m)=K m - grad L
        rows=[]
        for jj in range(3):
            Kj=[np.array([[1,0],[0,0]]),np.array([[0,0],[0,1]]),np.array([[0,1],[1,0]])][jj]
            vals=np.array([0.5*P[i]@Kj@P[i] for i in range(3)])
            gL=np.linalg.solve(M,vals)[1:]
            rows.append(nu@(Kj@m-gL))
        return np.array(rows)@Hk
    def operator(s,mode,Dmat=None):
        """list of (area, 3 x N curvature operator)"""
        ops=[]
        fits=[s.hessian_fit(e) for e in range(s.E)] if mode!='hinge' else None
        for e in range(s.E):
            ks=[s.kind(e,k) for k in range(3)];info=[s.edge_info(e,k) for k in range(3)]
            J=np.array([s.theta_row(e,k) for k in range(3)])
            hinge=np.array([[l/(2*s.A[e])*nu[0]**2,l/(2*s.A[e])*nu[1]**2,l/(2*s.A[e])*nu[0]*nu[1]] for (p,q,nu,l) in info]).T
            if mode=='hinge': ops.append((s.A[e],hinge@J));continue
            if mode=='exact':
                ops.append((s.A[e],fits[e] if fits[e] is not None else hinge@J));continue
            # morley: shared mid-edge slope
            S=[];freek=[]
            for k in range(3):
                p,q,nu,l=info[k]
                if ks[k]=='clamp': S.append(0.5*J[k]);continue   # absolute slope 0: relative -g.nu = theta/2
                if ks[k]=='free': S.append(np.zeros(s.N));freek.append(k);continue
                (e2,k2)=[x for x in s.emap[frozenset((p,q))] if x[0]!=e][0]
                cands=[]
                if fits[e] is not None: cands.append(s.rel_slope_own(e,k,fits[e]))
                if fits[e2] is not None: cands.append(J[k]-s.rel_slope_own(e2,k2,fits[e2]))
                S.append(np.mean(cands,axis=0) if cands else 0.5*J[k])
            Kop=sum((info[k][3]/s.A[e])*np.outer([info[k][2][0]**2,info[k][2][1]**2,info[k][2][0]*info[k][2][1]],S[k]) for k in range(3))
            for k in freek:   # condense: M_nn = 0 on the free edge
                nu=info[k][2];a=np.array([nu[0]**2,nu[1]**2,nu[0]*nu[1]])
                Dv=Dmat@np.array([a[0],a[1],2*a[2]])   # M for K = nu nu (engineering twist 2K12 in Dmat)
                # M = Dmat @ [K11,K22,2K12]; choose s: nn.M(K + l/A s a)=0
                conv=np.array([[1,0,0],[0,1,0],[0,0,2]])
                mrow=np.array([a[0],a[1],2*a[2]])@Dmat@conv
                denom=mrow@(info[k][3]/s.A[e]*a)
                Kop=Kop-np.outer(info[k][3]/s.A[e]*a,(mrow@Kop)/denom)
            ops.append((s.A[e],Kop))
        return ops
    def stiffness(s,ops,Dmat):
        H=np.zeros((s.N,s.N));conv=np.diag([1,1,2.])
        for a,K in ops: H+=a*(conv@K).T@Dmat@(conv@K)
        return H
