#!/usr/bin/python3
# Finite-strain companion of sphere_axi_fe.py: the same axisymmetric sphere (R = 5 mm) pressed by a
# rigid frictionless flat plate, but with mpmcd's compressible Neo-Hookean law instead of linear
# elasticity, independent of mpmcd (numpy/scipy only).
#
#   W(F) = mu/2 (tr C - 3) - mu ln J + lambda/2 (ln J)^2,   S = (lambda ln J - mu) C^-1 + mu I,
#   lambda = 3 MPa, mu = 1.5 MPa (E = 4 MPa, nu = 1/3 at small strain).
#
# Axisymmetric total Lagrangian: F = [[dr/dR, dr/dZ, 0], [dz/dR, dz/dZ, 0], [0, 0, r/R]]. The mesh
# is that of sphere_axi_fe.py (same code, same arguments -> the same nodes and triangles): linear
# triangles, in-plane F constant per triangle, the hoop stretch r/R taken at the quadrature points
# (default: the centroid, as the linear script's u_r/r; --quad 3 uses a 3-point rule), never on the
# axis. Unknowns: the deformed nodal positions. Stored energy
#   Psi(x) = sum_e sum_q w_q |A_e| 2 pi R_q W(F_eq),
# internal force = dPsi/dx, consistent tangent = d2Psi/dx2 (checked by finite differences at start-up,
# together with W -> P = F S -> dP/dF by finite differences of W).
# BCs: r = 0 on the axis, z = 0 on the centre plane (symmetry), plate at z = R - delta; exact
# node-wise active set on the arc nodes (active node: z = R - delta, r free = frictionless; released
# when its reaction turns tensile, activated when it penetrates), iterated to a fixed point at every
# load increment, full Newton at fixed active set. Displacement-controlled: delta/D from 0 in
# `--sub` increments per 0.0025.
# Force = -(sum of the z internal forces of the active nodes) (the 2 pi R weight is in Psi, so it is
# the force on the whole plate); contact radius a = the largest deformed r of an active node (as the
# linear script); a_int (log only) = the edge interpolated from the gaps of the first two free nodes
# assuming gap ~ (r - a)^(3/2).
# Energy check: plate work int F d delta (trapezoid over all increments) against Psi.
#
# Usage: /usr/bin/python3 sphere_axi_neo_hookean.py [--hmin 0.00125] [--grow 0.05] [--sub 4]
#        [--quad 1] [--dmax 0.05] [--out reference_neo_hookean.txt] [--lin reference.txt]
import os
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import argparse
import sys
import time
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.spatial import Delaunay

ap = argparse.ArgumentParser()
ap.add_argument("--hmin", type=float, default=0.00125, help="element size at the pole / R")
ap.add_argument("--grow", type=float, default=0.05, help="size growth per distance to the pole")
ap.add_argument("--sub", type=int, default=4, help="load increments per delta/D = 0.0025")
ap.add_argument("--quad", type=int, default=1, choices=[1, 3], help="points per triangle")
ap.add_argument("--dmax", type=float, default=0.05, help="last delta/D")
ap.add_argument("--rows", default=None, help="comma list of delta/D rows instead of 0.0025..dmax")
ap.add_argument("--out", default=None, help="write the reference table here")
ap.add_argument("--lin", default=None, help="linear table to compare with (reference.txt)")
ap.add_argument("--dat", default=None, help="write a full-precision table (F, a, Psi, plate work) here")
ap.add_argument("--nocheck", action="store_true")
args = ap.parse_args()

R = 5e-3
E, nu = 4e6, 1.0 / 3.0
lam = E * nu / ((1 + nu) * (1 - 2 * nu))  # 3e6
mu = E / (2 * (1 + nu))                    # 1.5e6
Estar = E / (1 - nu**2)
hmin = args.hmin * R
grow = args.grow
t0 = time.time()
log = lambda *a: print(*a, file=sys.stderr, flush=True)

# ---------------------------------------------------------------------------------------------
# Material: W, P (first Piola) and A = dP/dF on the 5 non-zero components (11, 12, 21, 22, 33)
# ---------------------------------------------------------------------------------------------
IDX = [(0, 0), (0, 1), (1, 0), (1, 1), (2, 2)]


def material(f5):
    """f5[..., 5] = F11, F12, F21, F22, F33 -> W, P5, A5 (5x5)."""
    F11, F12, F21, F22, F33 = (f5[..., k] for k in range(5))
    d2 = F11 * F22 - F12 * F21
    J = d2 * F33
    lnJ = np.log(J)
    W = 0.5 * mu * (F11**2 + F12**2 + F21**2 + F22**2 + F33**2 - 3) - mu * lnJ + 0.5 * lam * lnJ**2
    Fi = np.zeros(f5.shape[:-1] + (3, 3))  # F^-1
    Fi[..., 0, 0] = F22 / d2; Fi[..., 0, 1] = -F12 / d2
    Fi[..., 1, 0] = -F21 / d2; Fi[..., 1, 1] = F11 / d2
    Fi[..., 2, 2] = 1.0 / F33
    P5 = np.empty(f5.shape)
    for a, (i, Jx) in enumerate(IDX):  # P_iJ = mu F_iJ + (lam lnJ - mu) F^-1_Ji
        P5[..., a] = mu * f5[..., a] + (lam * lnJ - mu) * Fi[..., Jx, i]
    A5 = np.empty(f5.shape + (5,))
    for a, (i, Jx) in enumerate(IDX):
        for b, (k, L) in enumerate(IDX):
            # A_iJkL = mu d_ik d_JL + (mu - lam lnJ) Fi_Li Fi_Jk + lam Fi_Ji Fi_Lk
            A5[..., a, b] = (mu * (i == k) * (Jx == L) + (mu - lam * lnJ) * Fi[..., L, i] * Fi[..., Jx, k]
                             + lam * Fi[..., Jx, i] * Fi[..., L, k])
    return W, P5, A5


def check_constitutive(seed=1):
    """FD checks: P = dW/dF (3D, full 3x3 F against S = (lam ln J - mu) C^-1 + mu I) and
    A5 = dP5/dF5; returns the worst relative errors."""
    rng = np.random.default_rng(seed)

    def W3(F):
        C = F.T @ F
        J = np.linalg.det(F)
        return 0.5 * mu * (np.trace(C) - 3) - mu * np.log(J) + 0.5 * lam * np.log(J) ** 2

    eW = eS = eA = 0.0
    for _ in range(5):
        F = np.eye(3) + 0.3 * rng.standard_normal((3, 3))
        if np.linalg.det(F) < 0.2:
            continue
        C = F.T @ F
        J = np.linalg.det(F)
        S = (lam * np.log(J) - mu) * np.linalg.inv(C) + mu * np.eye(3)
        P = F @ S
        Pfd = np.zeros((3, 3))
        eps = 1e-6
        for i in range(3):
            for j in range(3):
                Fp = F.copy(); Fp[i, j] += eps
                Fm = F.copy(); Fm[i, j] -= eps
                Pfd[i, j] = (W3(Fp) - W3(Fm)) / (2 * eps)
        eW = max(eW, np.abs(Pfd - P).max() / np.abs(P).max())
        # the 5-component (axisymmetric) implementation against the 3D formulas
        f5 = np.array([F[0, 0], F[0, 1], F[1, 0], F[1, 1], 1.0 + 0.3 * rng.standard_normal()])
        if f5[4] < 0.3 or f5[0] * f5[3] - f5[1] * f5[2] < 0.2:
            continue
        F3 = np.array([[f5[0], f5[1], 0], [f5[2], f5[3], 0], [0, 0, f5[4]]])
        S3 = (lam * np.log(np.linalg.det(F3)) - mu) * np.linalg.inv(F3.T @ F3) + mu * np.eye(3)
        P3 = F3 @ S3
        Wv, P5, A5 = material(f5)
        eS = max(eS, max(abs(P5[a] - P3[i, j]) for a, (i, j) in enumerate(IDX)) / np.abs(P3).max()
                 + abs(Wv - W3(F3)) / abs(Wv))
        Afd = np.zeros((5, 5))
        for b in range(5):
            fp = f5.copy(); fp[b] += eps
            fm = f5.copy(); fm[b] -= eps
            Afd[:, b] = (material(fp)[1] - material(fm)[1]) / (2 * eps)
        eA = max(eA, np.abs(Afd - A5).max() / np.abs(A5).max())
    return eW, eS, eA


# ---------------------------------------------------------------------------------------------
# Mesh: identical to sphere_axi_fe.py
# ---------------------------------------------------------------------------------------------
def size(p):
    return hmin + grow * np.hypot(p[..., 0], p[..., 1] - R)


pts = [(0.0, 0.0)]
rho = R
rings = []
while rho > 0:
    rings.append(rho)
    h = size(np.array([0.0, rho]))
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
P = np.array(pts)
P = np.unique(np.round(P / (1e-9 * R)) * (1e-9 * R), axis=0)
T = Delaunay(P).simplices
a2 = (P[T[:, 1], 0] - P[T[:, 0], 0]) * (P[T[:, 2], 1] - P[T[:, 0], 1]) - (P[T[:, 2], 0] - P[T[:, 0], 0]) * (P[T[:, 1], 1] - P[T[:, 0], 1])
T = T[np.abs(a2) > 1e-14 * R * R]
a2 = a2[np.abs(a2) > 1e-14 * R * R]
T[a2 < 0] = T[a2 < 0][:, [0, 2, 1]]  # counter-clockwise
n, ne = len(P), len(T)
log(f"nodes {n}, triangles {ne}, hmin = {hmin/R:.4f} R, grow {grow}, quad {args.quad}, sub {args.sub}")

Xr, Xz = P[T, 0], P[T, 1]
A2 = (Xr[:, 1] - Xr[:, 0]) * (Xz[:, 2] - Xz[:, 0]) - (Xr[:, 2] - Xr[:, 0]) * (Xz[:, 1] - Xz[:, 0])
assert (A2 > 0).all()
bN = np.stack([Xz[:, 1] - Xz[:, 2], Xz[:, 2] - Xz[:, 0], Xz[:, 0] - Xz[:, 1]], 1) / A2[:, None]  # dN/dR
cN = np.stack([Xr[:, 2] - Xr[:, 1], Xr[:, 0] - Xr[:, 2], Xr[:, 1] - Xr[:, 0]], 1) / A2[:, None]  # dN/dZ
if args.quad == 1:
    Nq = np.array([[1 / 3, 1 / 3, 1 / 3]]); wq = np.array([1.0])
else:
    Nq = np.array([[2 / 3, 1 / 6, 1 / 6], [1 / 6, 2 / 3, 1 / 6], [1 / 6, 1 / 6, 2 / 3]]); wq = np.full(3, 1 / 3)
nq = len(wq)
Rq = Xr @ Nq.T                                    # (ne, nq) reference radius of the points
assert (Rq > 0).all()
Wt = 2 * np.pi * Rq * (0.5 * A2)[:, None] * wq    # (ne, nq) integration weights (full revolution)
G = np.zeros((ne, nq, 5, 6))                      # dF5/d(element dofs r0 z0 r1 z1 r2 z2)
for i in range(3):
    G[:, :, 0, 2 * i] = bN[:, i, None]
    G[:, :, 1, 2 * i] = cN[:, i, None]
    G[:, :, 2, 2 * i + 1] = bN[:, i, None]
    G[:, :, 3, 2 * i + 1] = cN[:, i, None]
    G[:, :, 4, 2 * i] = Nq[None, :, i] / Rq
edofs = np.stack([2 * T[:, 0], 2 * T[:, 0] + 1, 2 * T[:, 1], 2 * T[:, 1] + 1, 2 * T[:, 2], 2 * T[:, 2] + 1], 1)
Krows = np.repeat(edofs, 6, axis=1).ravel()
Kcols = np.tile(edofs, (1, 6)).ravel()
ndof = 2 * n


def deform(x):
    xr, xz = x[0::2][T], x[1::2][T]
    f5 = np.empty((ne, nq, 5))
    f5[..., 0] = (xr * bN).sum(1)[:, None]
    f5[..., 1] = (xr * cN).sum(1)[:, None]
    f5[..., 2] = (xz * bN).sum(1)[:, None]
    f5[..., 3] = (xz * cN).sum(1)[:, None]
    f5[..., 4] = (xr @ Nq.T) / Rq
    return f5


def energy(x):
    W, _, _ = material(deform(x))
    return float((Wt * W).sum())


def assemble(x, tangent=True):
    W, P5, A5 = material(deform(x))
    if not np.isfinite(W).all() or (deform(x)[..., 4] <= 0).any():
        raise FloatingPointError("inverted element")
    fe = np.einsum("eq,eqai,eqa->ei", Wt, G, P5)
    f = np.bincount(edofs.ravel(), fe.ravel(), minlength=ndof)
    if not tangent:
        return f, None
    Ke = np.einsum("eq,eqai,eqab,eqbj->eij", Wt, G, A5, G)
    K = sp.csr_matrix((Ke.ravel(), (Krows, Kcols)), shape=(ndof, ndof))
    return f, K


X0 = P.ravel().copy()  # reference positions (r0 z0 r1 z1 ...)
tol = 1e-9 * R
axis = np.where(P[:, 0] < tol)[0]
base = np.where(P[:, 1] < tol)[0]
arc = np.where(np.abs(np.hypot(P[:, 0], P[:, 1]) - R) < 1e-6 * R)[0]
arc = arc[np.argsort(P[arc, 0])]  # from the pole outwards
fixed = np.union1d(2 * axis, 2 * base + 1)

# ---------------------------------------------------------------------------------------------
# Start-up checks
# ---------------------------------------------------------------------------------------------
if not args.nocheck:
    eW, eS, eA = check_constitutive()
    log(f"check: W -> P = F S (FD of W, 3D) max rel err {eW:.1e}; axisymmetric P5/W vs 3D {eS:.1e};"
        f" A5 vs FD of P5 {eA:.1e}")
    assert eW < 1e-6 and eS < 1e-12 and eA < 1e-6
    rng = np.random.default_rng(2)
    # a smooth, large deformed state: squeeze plus bulge plus noise (strains ~ 10-20 %)
    xs = X0.copy()
    xs[0::2] = P[:, 0] * (1.08 + 0.1 * P[:, 1] / R)
    xs[1::2] = P[:, 1] * (0.9 - 0.1 * (P[:, 0] / R) ** 2)
    xs += 0.05 * hmin * rng.standard_normal(ndof)  # small against the smallest element
    xs[2 * axis] = 0.0
    f, K = assemble(xs)
    # directions: white nodal noise scaled to max |v| = hmin; central differences with a step
    # eps * v, best of a few eps (truncation ~ eps^2 against round-off ~ 1e-16 / eps)
    worst = eR = 0.0
    for k in range(3):
        v = rng.standard_normal(ndof)
        v[2 * axis] = 0.0
        v *= hmin / np.abs(v).max()
        Kv = K @ v
        best = bestR = np.inf
        for eps in (1e-3, 1e-4, 1e-5, 1e-6):
            fp, _ = assemble(xs + eps * v, False)
            fm, _ = assemble(xs - eps * v, False)
            best = min(best, np.linalg.norm((fp - fm) / (2 * eps) - Kv) / np.linalg.norm(Kv))
            dE = (energy(xs + eps * v) - energy(xs - eps * v)) / (2 * eps)
            bestR = min(bestR, abs(dE - f @ v) / abs(f @ v))
        worst = max(worst, best)
        eR = max(eR, bestR)
    log(f"check: tangent K v vs FD of the residual at a deformed state: rel err {worst:.1e};"
        f" residual f.v vs FD of Psi: rel err {eR:.1e}")
    assert worst < 1e-5 and eR < 1e-5


# ---------------------------------------------------------------------------------------------
# Quasi-static loading with contact
# ---------------------------------------------------------------------------------------------
FSCALE = mu * R * R  # 37.5 N


def newton(x, active, zp):
    act = np.array(sorted(active), dtype=int)
    presc = np.union1d(fixed, 2 * act + 1)
    target = x.copy()
    target[2 * axis] = 0.0
    target[2 * base + 1] = 0.0
    target[2 * act + 1] = zp
    free = np.setdiff1d(np.arange(ndof), presc)
    x = x.copy()
    res = np.inf
    for it in range(50):
        f, K = assemble(x)
        dp = target[presc] - x[presc]  # non-zero in the first iteration only: linearised lifting
        res = np.abs(f[free]).max()
        if res < 1e-12 * FSCALE and it > 0:
            return x, f, it
        Kff = K[free][:, free].tocsc()
        rhs = -f[free]
        if np.abs(dp).max() > 0:
            rhs = rhs - K[free][:, presc] @ dp
        dx = spla.spsolve(Kff, rhs)
        step = 1.0
        for _ in range(30):
            xt = x.copy(); xt[free] += step * dx; xt[presc] += step * dp
            try:
                assemble(xt, False)
                break
            except FloatingPointError:
                step *= 0.5
        else:
            raise RuntimeError("cannot avoid inverted elements")
        x = xt
        if step == 1.0 and np.abs(dx).max() < 1e-14 * R and it > 0:
            f, _ = assemble(x, False)
            return x, f, it
    raise RuntimeError(f"Newton did not converge, residual {res:.2e} N")


def contact_step(x, active, delta):
    zp = R - delta
    for outer in range(60):
        x, f, it = newton(x, active, zp)
        new = set()
        for i in arc:
            if i in active:
                if f[2 * i + 1] <= 0.0:  # compressive reaction: stays
                    new.add(int(i))
            elif x[2 * i + 1] > zp + 1e-12 * R:
                new.add(int(i))
        if not new:
            new = {int(arc[0])}
        if new == active:
            return x, f, active, outer
        active = new
    raise RuntimeError("no active-set convergence")


def contact_radius(x, active):
    act = np.array(sorted(active))
    ia = act[np.argmax(x[2 * act])]
    a = x[2 * ia]
    # interpolation with the gaps of the next two free arc nodes (gap ~ (r - a)^1.5)
    k = np.where(arc == ia)[0][0]
    try:
        i1, i2 = arc[k + 1], arc[k + 2]
        zp = x[2 * ia + 1]
        g1, g2 = zp - x[2 * i1 + 1], zp - x[2 * i2 + 1]
        r1, r2 = x[2 * i1], x[2 * i2]
        q = (g1 / g2) ** (2.0 / 3.0)  # (r1 - a)/(r2 - a)
        ai = (r1 - q * r2) / (1 - q)
        if not (a - 1e-9 <= ai <= r1):
            ai = np.nan
    except (IndexError, ZeroDivisionError):
        ai = np.nan
    return a, ai


if args.rows:
    rows_target = [float(v) for v in args.rows.split(",")]
else:
    rows_target = list(np.round(np.arange(1, int(round(args.dmax / 0.0025)) + 1) * 0.0025, 6))
steps = []  # (delta/D, is a row)
prev = 0.0
for rt in rows_target:
    for k in range(1, args.sub + 1):
        steps.append((prev + (rt - prev) * k / args.sub, k == args.sub))
    prev = rt
x = X0.copy()
xprev, dprev = X0.copy(), 0.0
active = {int(arc[0])}
work, Fold, dold = 0.0, 0.0, 0.0
out = []
for dD, is_row in steps:
    delta = dD * 2 * R
    # predictor: linear extrapolation of the last increment
    xg = x + (x - xprev) * ((delta - dold) / (dold - dprev) if dold > dprev else 0.0)
    xprev, dprev = x, dold
    x, f, active, nouter = contact_step(xg, set(active), delta)
    act = np.array(sorted(active))
    F = -f[2 * act + 1].sum()
    work += 0.5 * (F + Fold) * (delta - dold)
    Fold, dold = F, delta
    if is_row:
        a, ai = contact_radius(x, active)
        Psi = energy(x)
        Fh = 4.0 / 3.0 * Estar * np.sqrt(R) * delta**1.5
        out.append((dD, F, Fh, a, ai, Psi, work, len(active)))
        log(f"delta/D {dD:.5f}  F {F:.7f} N  a/R {a/R:.4f} (interp {ai/R:.4f})  active {len(active)}"
            f"  Psi {Psi:.6e} J  plate work {work:.6e} J  (work-Psi)/Psi {(work-Psi)/Psi:+.2e}"
            f"  active-set passes {nouter}  t {time.time()-t0:.0f} s")

lines = [f"nodes {n}, triangles {ne}, hmin = {hmin/R:.4f} R",
         "delta/D  F_FE [N]  F_Hertz [N]  F_FE/F_Hertz  a/R  a_Hertz/R"]
for dD, F, Fh, a, ai, Psi, work, na in out:
    delta = dD * 2 * R
    lines.append(f"{dD:.4f}  {F:.5f}  {Fh:.5f}  {F/Fh:.4f}  {a/R:.4f}  {np.sqrt(R*delta)/R:.4f}")
print("\n".join(lines))
if args.out:
    with open(args.out, "w") as fh:
        fh.write("\n".join(lines) + "\n")
# machine-readable full precision (for the step / mesh comparisons)
if args.dat:
    with open(args.dat, "w") as fh:
        fh.write("# delta/D F[N] a/R a_interp/R Psi[J] plate_work[J] n_active\n")
        for dD, F, Fh, a, ai, Psi, work, na in out:
            fh.write(f"{dD:.6f} {F:.10e} {a/R:.6f} {ai/R:.6f} {Psi:.10e} {work:.10e} {na}\n")
if args.lin:
    lin = {}
    for line in open(args.lin):
        p = line.split()
        try:
            lin[round(float(p[0]), 6)] = (float(p[1]), float(p[4]))
        except (ValueError, IndexError):
            pass
    print("\ndelta/D  F_NH [N]  F_linear [N]  F_NH/F_linear  a_NH/R  a_linear/R")
    for dD, F, Fh, a, ai, Psi, work, na in out:
        if round(dD, 6) in lin:
            Fl, al = lin[round(dD, 6)]
            print(f"{dD:.4f}  {F:.5f}  {Fl:.5f}  {F/Fl:.4f}  {a/R:.4f}  {al:.4f}")
log(f"total {time.time()-t0:.0f} s")
