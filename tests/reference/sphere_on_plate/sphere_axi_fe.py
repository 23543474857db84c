# Reference for the 3D Hertz test (tests/support/sphere_squeeze.hpp, docs/three_d.md): an
# axisymmetric linear-elastic finite-element solution of an elastic sphere (R = 5 mm, E = 4 MPa,
# nu = 1/3: the small-strain moduli of mpmcd's Neo-Hookean gel, lambda = 3 MPa, mu = 1.5 MPa)
# pressed by a rigid frictionless flat, independent of mpmcd.
#
# Quarter meridian (r >= 0, z >= 0) of the sphere, linear triangles (CST) with the hoop strain
# u_r / r at the centroid, u_r = 0 on the axis, u_z = 0 on z = 0 (the symmetry plane through the
# centre, as the two-plate problem), the plate at z = R - delta; exact node-wise active set on the
# arc nodes (an active node gets u_z = R - delta - z, released when the plate would pull it).
# Force = the plate's reaction (2 pi r weighting in the stiffness), contact radius = the largest
# deformed r of an active node. delta is the approach of the plate to the centre.
#
# Usage: python3 sphere_axi_fe.py [hmin/R] [delta/D list] [growth]   (defaults 0.004, a list,
# 0.1). The stored reference.txt: python3 sphere_axi_fe.py 0.00125 0.0025,0.005,...,0.05 0.05
# (4037 nodes, about 1 minute). Element size hmin at the pole growing by `growth` times the
# distance to it; hmin 0.005 -> 0.0025 -> 0.00125 R and growth 0.1 -> 0.05 change F by < 0.4 %.
import sys
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.spatial import Delaunay

R = 5e-3
E, nu = 4e6, 1.0 / 3.0
lam = E * nu / ((1 + nu) * (1 - 2 * nu))
mu = E / (2 * (1 + nu))
Estar = E / (1 - nu**2)
hmin = float(sys.argv[1]) * R if len(sys.argv) > 1 else 0.004 * R
grow = float(sys.argv[3]) if len(sys.argv) > 3 else 0.1

def size(p):  # local element size: hmin at the pole, growing with the distance to it
    return hmin + grow * np.hypot(p[..., 0], p[..., 1] - R)

# Points: rings rho = const with spacing size(); arcs sampled with local size.
pts = [(0.0, 0.0)]
rho = R
rings = []
while rho > 0:
    rings.append(rho)
    h = size(np.array([0.0, rho]))  # at the axis, at this radius
    # the ring's spacing: the size at its pole point
    rho -= max(h, 1e-12)
for rho in rings:
    th = 0.0
    ring = []
    while th < np.pi / 2:
        p = np.array([rho * np.sin(th), rho * np.cos(th)])
        ring.append(p)
        th += size(p) / rho
    ring.append(np.array([rho, 0.0]))
    pts.extend(map(tuple, ring))
# axis and base lines
P = np.array(pts)
P = np.unique(np.round(P / (1e-9 * R)) * (1e-9 * R), axis=0)
tri = Delaunay(P)
T = tri.simplices
# drop slivers outside the (convex) quarter disk: none expected; drop zero-area ones
a2 = (P[T[:, 1], 0] - P[T[:, 0], 0]) * (P[T[:, 2], 1] - P[T[:, 0], 1]) - (P[T[:, 2], 0] - P[T[:, 0], 0]) * (P[T[:, 1], 1] - P[T[:, 0], 1])
T = T[np.abs(a2) > 1e-14 * R * R]
n = len(P)
print(f"nodes {n}, triangles {len(T)}, hmin = {hmin/R:.4f} R", file=sys.stderr)

D = np.array([[lam + 2 * mu, lam, lam, 0], [lam, lam + 2 * mu, lam, 0], [lam, lam, lam + 2 * mu, 0], [0, 0, 0, mu]])
rows, cols, vals = [], [], []
for t in T:
    x = P[t, 0]; z = P[t, 1]
    A2 = (x[1] - x[0]) * (z[2] - z[0]) - (x[2] - x[0]) * (z[1] - z[0])
    A = 0.5 * abs(A2)
    if A2 < 0:
        t = t[[0, 2, 1]]; x = P[t, 0]; z = P[t, 1]; A2 = -A2
    b = np.array([z[1] - z[2], z[2] - z[0], z[0] - z[1]]) / A2  # dN/dr
    c = np.array([x[2] - x[1], x[0] - x[2], x[1] - x[0]]) / A2  # dN/dz
    rc = x.mean()
    B = np.zeros((4, 6))
    for i in range(3):
        B[0, 2 * i] = b[i]
        B[1, 2 * i + 1] = c[i]
        B[2, 2 * i] = 1.0 / 3.0 / rc  # N_i / r at the centroid
        B[3, 2 * i] = c[i]
        B[3, 2 * i + 1] = b[i]
    Ke = 2 * np.pi * rc * A * B.T @ D @ B
    dofs = np.array([[2 * i, 2 * i + 1] for i in t]).ravel()
    rows.append(np.repeat(dofs, 6)); cols.append(np.tile(dofs, 6)); vals.append(Ke.ravel())
K = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(2 * n, 2 * n))

tol = 1e-9 * R
axis = np.where(P[:, 0] < tol)[0]
base = np.where(P[:, 1] < tol)[0]
arc = np.where(np.abs(np.hypot(P[:, 0], P[:, 1]) - R) < 1e-6 * R)[0]
fixed = set(2 * axis) | set(2 * base + 1)

def solve(delta):
    active = set(arc[P[arc, 1] > R - delta - 1e-12].tolist()) or {int(arc[np.argmax(P[arc, 1])])}
    for it in range(100):
        presc = {}
        for i in active:
            presc[2 * i + 1] = (R - delta) - P[i, 1]
        for d in fixed:
            presc.setdefault(d, 0.0)
        pd = np.array(sorted(presc)); pv = np.array([presc[d] for d in pd])
        free = np.setdiff1d(np.arange(2 * n), pd)
        u = np.zeros(2 * n); u[pd] = pv
        rhs = -K[free][:, pd] @ pv
        u[free] = spla.spsolve(K[free][:, free].tocsc(), rhs)
        f = K @ u  # reactions at prescribed dofs
        new = set()
        for i in arc:
            if i in active:
                if f[2 * i + 1] <= 0:  # the plate pushes down: reaction on the node is negative in z
                    new.add(int(i))
            else:
                if P[i, 1] + u[2 * i + 1] > R - delta + 1e-12 * R:
                    new.add(int(i))
        if new == active:
            F = -sum(f[2 * i + 1] for i in active)
            a = max(P[i, 0] + u[2 * i] for i in active)
            return F, a, it
        active = new
    raise RuntimeError("no active-set convergence")

print("delta/D  F_FE [N]  F_Hertz [N]  F_FE/F_Hertz  a/R  a_Hertz/R")
for x in [float(v) for v in (sys.argv[2].split(",") if len(sys.argv) > 2 else ["0.005", "0.01", "0.02", "0.03", "0.04", "0.05"])]:
    delta = x * 2 * R
    F, a, it = solve(delta)
    Fh = 4.0 / 3.0 * Estar * np.sqrt(R) * delta**1.5
    print(f"{x:.4f}  {F:.5f}  {Fh:.5f}  {F/Fh:.4f}  {a/R:.4f}  {np.sqrt(R*delta)/R:.4f}", flush=True)
