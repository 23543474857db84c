#!/usr/bin/python3
"""Finite-element reference: elastic disk squeezed between two rigid, flat, frictionless plates.

What is solved
--------------
Plane strain, quasi-static, per unit thickness.  A disk of radius R (default 1e-3 m) made of a
compressible Neo-Hookean material is pressed between two rigid flat frictionless plates that
each move toward the centre by Delta/2 (Delta = loss of diameter).  Because of the symmetry only
the quarter disk 0 <= X, 0 <= Y, X^2 + Y^2 <= R^2 (reference coordinates) is modelled:
    u_x = 0 on X = 0,      u_y = 0 on Y = 0,
    unilateral frictionless contact with the top plate y = h = R - Delta/2 on the arc:
        g = h - (Y + u_y) >= 0,  t_n >= 0 (compressive),  t_n g = 0,  tangential traction = 0.

Material (SI units, Pa):
    W(F) = mu/2 (tr C - 2) - mu ln J + lambda/2 (ln J)^2          [J/m^3]
with C = F^T F the 2x2 right Cauchy-Green tensor (F33 = 1, so tr C_3D - 3 = tr C - 2), J = det F.
Then S = 2 dW/dC = (lambda ln J - mu) C^-1 + mu I, i.e. Kirchhoff stress
tau = mu (b - I) + lambda ln J I (checked numerically by check_constitutive() below).

Discretisation
--------------
* lambda = 0: pure displacement, continuous P2 triangles.
* lambda > 0: mixed displacement-pressure (Taylor-Hood P2-P1) with p = lambda ln J, i.e. the
  stationary point of   Pi(u, p) = int [ mu/2 (tr C - 2) - mu ln J + p ln J - p^2/(2 lambda) ] dA,
  free of volumetric locking for lambda/mu = 66.7.
* Mesh: gmsh (Frontal-Delaunay), element size hc along the upper arc (theta >= theta_c, where the
  contact zone lives), graded to hfar in the interior; straight-sided elements with vertices on
  the circle.
* Contact: exact node-wise active set on the arc nodes (P2 vertices and edge midpoints):
  active nodes get the Dirichlet condition u_y = h - Y (u_x free = frictionless), a node is
  released when its reaction becomes tensile and activated when it penetrates the plate
  (primal-dual active set, updated inside the Newton iterations of each load increment).
* Loading: Delta increased in small increments, full Newton (LU, MUMPS) at every increment.

Outputs (full disk, per unit thickness)
---------------------------------------
    P  [N/m]  plate force = 2 x (sum of contact reactions of the quarter)
    a  [m]    contact half-width in the deformed configuration (x of the outermost contact node,
              and an interpolated value using the gap g ~ (x - a)^(3/2) of the first free nodes);
              a_ref = the same edge located by its reference coordinate X (for the Hertz check)
    E  [J/m]  stored energy = 4 int_quarter W(F) dA (reference area)
    Wp [J/m]  plate work = int_0^Delta P dDelta' (trapezoidal rule over the increments)

Run   /usr/bin/python3 squeezed_disk_fenics.py --lam 3e6 --level 2 --out run.csv
(needs the Debian packages python3-dolfin and python3-gmsh).
"""
import argparse
import math
import sys
import time

import numpy as np

import dolfin as df
import gmsh

df.set_log_level(df.LogLevel.WARNING)
df.parameters["form_compiler"]["cpp_optimize"] = True
df.parameters["form_compiler"]["cpp_optimize_flags"] = "-O2"


# ---------------------------------------------------------------------------------------------
# Constitutive check
# ---------------------------------------------------------------------------------------------
def check_constitutive(mu=1.5e6, lam=3e6, seed=1):
    """Finite-difference check that W gives S = (lam ln J - mu) C^-1 + mu I (i.e. P = F S)."""
    rng = np.random.default_rng(seed)

    def W(F):
        C = F.T @ F
        J = np.linalg.det(F)
        return 0.5 * mu * (np.trace(C) - 2) - mu * np.log(J) + 0.5 * lam * np.log(J) ** 2

    worst = 0.0
    for _ in range(5):
        F = np.eye(2) + 0.3 * rng.standard_normal((2, 2))
        if np.linalg.det(F) < 0.2:
            continue
        C = F.T @ F
        J = np.linalg.det(F)
        S = (lam * np.log(J) - mu) * np.linalg.inv(C) + mu * np.eye(2)
        P = F @ S
        Pfd = np.zeros((2, 2))
        eps = 1e-6
        for i in range(2):
            for j in range(2):
                Fp = F.copy(); Fp[i, j] += eps
                Fm = F.copy(); Fm[i, j] -= eps
                Pfd[i, j] = (W(Fp) - W(Fm)) / (2 * eps)
        worst = max(worst, np.abs(Pfd - P).max() / np.abs(P).max())
    return worst


# ---------------------------------------------------------------------------------------------
# Mesh
# ---------------------------------------------------------------------------------------------
def mesh_parameters(level, R):
    """Mesh family: every size halves from one level to the next."""
    f = 2.0 ** level
    return dict(hc=R / (25.0 * f), hside=R / (10.0 * f), hfar=R / (5.0 * f),
                theta_c=25.0, dist_max=0.15 * R)


def build_mesh(R, hc, hside, hfar, theta_c, dist_max):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("quarter_disk")
    g = gmsh.model.geo
    tc = math.radians(theta_c)
    p0 = g.addPoint(0, 0, 0, hfar)
    pA = g.addPoint(R, 0, 0, hside)
    pC = g.addPoint(R * math.cos(tc), R * math.sin(tc), 0, hc)
    pB = g.addPoint(0, R, 0, hc)
    l_bot = g.addLine(p0, pA)
    a_side = g.addCircleArc(pA, p0, pC)
    a_top = g.addCircleArc(pC, p0, pB)
    l_left = g.addLine(pB, p0)
    cl = g.addCurveLoop([l_bot, a_side, a_top, l_left])
    g.addPlaneSurface([cl])
    g.synchronize()
    fld = gmsh.model.mesh.field
    d1 = fld.add("Distance")
    fld.setNumbers(d1, "CurvesList", [a_top])
    fld.setNumber(d1, "NumPointsPerCurve", int(4 * R * (math.pi / 2 - tc) / hc) + 10)
    t1 = fld.add("Threshold")
    fld.setNumber(t1, "InField", d1)
    fld.setNumber(t1, "SizeMin", hc)
    fld.setNumber(t1, "SizeMax", hfar)
    fld.setNumber(t1, "DistMin", 0.0)
    fld.setNumber(t1, "DistMax", dist_max)
    d2 = fld.add("Distance")
    fld.setNumbers(d2, "CurvesList", [a_side])
    fld.setNumber(d2, "NumPointsPerCurve", int(4 * R * tc / hside) + 10)
    t2 = fld.add("Threshold")
    fld.setNumber(t2, "InField", d2)
    fld.setNumber(t2, "SizeMin", hside)
    fld.setNumber(t2, "SizeMax", hfar)
    fld.setNumber(t2, "DistMin", 0.0)
    fld.setNumber(t2, "DistMax", dist_max)
    fmin = fld.add("Min")
    fld.setNumbers(fmin, "FieldsList", [t1, t2])
    fld.setAsBackgroundMesh(fmin)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.Algorithm", 6)
    gmsh.model.mesh.generate(2)
    tags, xyz, _ = gmsh.model.mesh.getNodes()
    etypes, _, enodes = gmsh.model.mesh.getElements(2)
    tri = np.asarray(enodes[list(etypes).index(2)], dtype=np.int64).reshape(-1, 3)
    gmsh.finalize()
    xyz = np.asarray(xyz).reshape(-1, 3)[:, :2]
    used = np.unique(tri)
    pos = {int(t): i for i, t in enumerate(np.asarray(tags, dtype=np.int64))}
    new = {int(t): k for k, t in enumerate(used)}
    pts = np.array([xyz[pos[int(t)]] for t in used])
    cells = np.vectorize(lambda t: new[int(t)])(tri)
    # snap the boundary points exactly onto the symmetry lines / circle
    pts[np.abs(pts[:, 0]) < 1e-9 * R, 0] = 0.0
    pts[np.abs(pts[:, 1]) < 1e-9 * R, 1] = 0.0
    mesh = df.Mesh()
    ed = df.MeshEditor()
    ed.open(mesh, "triangle", 2, 2)
    ed.init_vertices(len(pts))
    ed.init_cells(len(cells))
    for i, p in enumerate(pts):
        ed.add_vertex(i, p)
    for i, c in enumerate(cells):
        # counter-clockwise orientation
        a, b, cc = pts[c[0]], pts[c[1]], pts[c[2]]
        if (b[0] - a[0]) * (cc[1] - a[1]) - (b[1] - a[1]) * (cc[0] - a[0]) < 0:
            c = [c[0], c[2], c[1]]
        ed.add_cell(i, np.array(c, dtype=np.uintp))
    ed.close()
    return mesh


# ---------------------------------------------------------------------------------------------
# Solver
# ---------------------------------------------------------------------------------------------
class SqueezedDisk:
    def __init__(self, mesh, R, mu, lam, qdeg=4, mixed=None, small_strain=False):
        self.R, self.mu, self.lam = R, mu, lam
        self.mixed = (lam > 0) if mixed is None else mixed
        cell = mesh.ufl_cell()
        Pu = df.VectorElement("P", cell, 2)
        if self.mixed:
            W = df.FunctionSpace(mesh, df.MixedElement([Pu, df.FiniteElement("P", cell, 1)]))
            Vu = W.sub(0)
        else:
            W = df.FunctionSpace(mesh, Pu)
            Vu = W
        self.W, self.Vu = W, Vu
        self.w = df.Function(W)
        if self.mixed:
            u, p = df.split(self.w)
        else:
            u = self.w
        I = df.Identity(2)
        F = I + df.grad(u)
        C = F.T * F
        J = df.det(F)
        lnJ = df.ln(J)
        mu_c, lam_c = df.Constant(mu), df.Constant(lam)
        W_u = 0.5 * mu_c * (df.tr(C) - 2) - mu_c * lnJ + 0.5 * lam_c * lnJ ** 2
        if self.mixed:
            psi = 0.5 * mu_c * (df.tr(C) - 2) - mu_c * lnJ + p * lnJ - p ** 2 / (2 * lam_c)
        else:
            psi = W_u
        if small_strain:
            # linear elasticity (only for the check against the linear 2D Hertz solution)
            eps = df.sym(df.grad(u))
            J = 1.0 + df.tr(eps)
            W_u = mu_c * df.inner(eps, eps) + 0.5 * lam_c * df.tr(eps) ** 2
            if self.mixed:
                psi = mu_c * df.inner(eps, eps) + p * df.tr(eps) - p ** 2 / (2 * lam_c)
            else:
                psi = W_u
        dxq = df.dx(metadata={"quadrature_degree": qdeg})
        self.Pi = psi * dxq
        self.E_form = W_u * dxq
        self.vol_form = J * dxq
        self.Res = df.derivative(self.Pi, self.w, df.TestFunction(W))
        self.Jac = df.derivative(self.Res, self.w, df.TrialFunction(W))

        # boundary facets: 1 = X=0, 2 = Y=0, 3 = arc
        ff = df.MeshFunction("size_t", mesh, 1, 0)
        tol = 1e-9 * R
        for f in df.facets(mesh):
            if f.exterior():
                m = f.midpoint()
                if abs(m.x()) < tol:
                    ff[f] = 1
                elif abs(m.y()) < tol:
                    ff[f] = 2
                else:
                    ff[f] = 3
        self.bcs = [df.DirichletBC(Vu.sub(0), df.Constant(0.0), ff, 1),
                    df.DirichletBC(Vu.sub(1), df.Constant(0.0), ff, 2)]
        self.sym_dofs = np.array(sorted(set(self.bcs[0].get_boundary_values().keys())
                                        | set(self.bcs[1].get_boundary_values().keys())),
                                 dtype=np.int64)
        self.symy_dofs = np.array(sorted(self.bcs[1].get_boundary_values().keys()), dtype=np.int64)
        X = W.tabulate_dof_coordinates().reshape(-1, 2)
        ydofs = df.DirichletBC(Vu.sub(1), df.Constant(0.0), ff, 3).get_boundary_values().keys()
        xdofs = df.DirichletBC(Vu.sub(0), df.Constant(0.0), ff, 3).get_boundary_values().keys()
        key = lambda d: (round(X[d, 0] / R * 1e9), round(X[d, 1] / R * 1e9))
        xmap = {key(d): d for d in xdofs}
        symy = set(self.symy_dofs.tolist())
        cy = [d for d in ydofs if d not in symy]
        cy.sort(key=lambda d: -math.atan2(X[d, 1], X[d, 0]))  # from the top (theta = 90 deg) down
        self.cy = np.array(cy, dtype=np.int64)
        self.cx = np.array([xmap[key(d)] for d in cy], dtype=np.int64)
        self.Xc = X[self.cy, 0].copy()
        self.Yc = X[self.cy, 1].copy()
        self.active = np.zeros(len(self.cy), dtype=bool)
        self.solver = df.PETScLUSolver("mumps")
        self.ndofs = W.dim()
        self.force_scale = mu * R

    # -----------------------------------------------------------------------------------------
    def solve(self, Delta, maxit=40, rtol=1e-10, verbose=False):
        """Equilibrium at plate position h = R - Delta/2. Returns (ok, iterations)."""
        h = self.R - 0.5 * Delta
        wv = self.w.vector()
        dw = df.Function(self.W)
        tol_g = 1e-9 * self.R          # activation threshold on penetration
        seen = {}
        for it in range(1, maxit + 1):
            A, b = df.assemble_system(self.Jac, -self.Res, self.bcs)
            rows = self.cy[self.active]
            wl = wv.get_local()
            A.ident(rows.astype(np.intc))
            bl = b.get_local()
            bl[rows] = (h - self.Yc[self.active]) - wl[rows]
            b.set_local(bl)
            b.apply("insert")
            self.solver.set_operator(A)
            try:
                self.solver.solve(dw.vector(), b)
            except RuntimeError:
                return False, it          # singular / failed factorisation: the caller cuts
            if not np.all(np.isfinite(dw.vector().get_local())):
                return False, it
            wv.axpy(1.0, dw.vector())
            # residual, reactions, gaps
            r = df.assemble(self.Res).get_local()
            wl = wv.get_local()
            lam_n = -r[self.cy]                    # compressive contact reaction > 0 [N/m]
            gap = h - (self.Yc + wl[self.cy])
            rfree = r.copy()
            rfree[self.sym_dofs] = 0.0
            rfree[self.cy[self.active]] = 0.0
            rnorm = np.linalg.norm(rfree)
            new_active = np.where(self.active, lam_n > 0.0, gap < -tol_g)
            changed = int(np.count_nonzero(new_active != self.active))
            dnorm = np.linalg.norm(dw.vector().get_local())
            if verbose:
                print(f"    it {it}: |r| = {rnorm:.3e}, |dw| = {dnorm:.3e}, "
                      f"active {int(self.active.sum())} -> {int(new_active.sum())}")
            if changed:
                k = new_active.tobytes()
                seen[k] = seen.get(k, 0) + 1
                if seen[k] > 3:
                    # cycling between two sets (P2 vertex / mid-node at the contact edge):
                    # keep the node active, i.e. accept the union
                    new_active = new_active | self.active
                self.active = new_active
                continue
            if rnorm < rtol * self.force_scale:
                return True, it
        return False, maxit

    # -----------------------------------------------------------------------------------------
    def outputs(self, Delta):
        h = self.R - 0.5 * Delta
        r = df.assemble(self.Res).get_local()
        wl = self.w.vector().get_local()
        lam_n = -r[self.cy]
        P_contact = 2.0 * lam_n[self.active].sum()
        P_sym = 2.0 * r[self.symy_dofs].sum()      # reaction on the plane Y = 0 (check)
        xdef = self.Xc + wl[self.cx]
        gap = h - (self.Yc + wl[self.cy])
        act = np.nonzero(self.active)[0]

        def edge(xc):
            """Contact edge along the coordinate xc of the arc nodes: x of the outermost active
            node, and an estimate between it and the first free node from g ~ (x - a)^(3/2)
            fitted through the gaps of the first two free nodes."""
            if not len(act):
                return 0.0, 0.0
            k = act.max()  # outermost (smallest theta) active node, nodes sorted by theta desc.
            a0 = xc[k]
            free = [j for j in range(k + 1, len(self.cy)) if not self.active[j]]
            if len(free) >= 2:
                j1, j2 = free[0], free[1]
                g1, g2 = gap[j1], gap[j2]
                x1, x2 = xc[j1], xc[j2]
                if g1 > 0 and g2 > g1 and x2 > x1 > a0:
                    q = (g1 / g2) ** (2.0 / 3.0)
                    return a0, min(max((q * x2 - x1) / (q - 1.0), a0), x1)
            return a0, a0

        a_node, a_interp = edge(xdef)
        _, a_ref = edge(self.Xc)
        E = 4.0 * df.assemble(self.E_form)
        Pi = 4.0 * df.assemble(self.Pi)
        area = 4.0 * df.assemble(self.vol_form)
        pen = max(0.0, float(-gap.min()))
        theta = math.degrees(math.atan2(self.Yc[act.max()], self.Xc[act.max()])) if len(act) else 90.0
        return dict(P=P_contact, P_sym=P_sym, a_node=a_node, a=a_interp, a_ref=a_ref, E=E, Pi=Pi,
                    area=area, penetration=pen, n_active=int(self.active.sum()),
                    theta_ref_deg=theta)


def load_path(dmax=0.40, fine_until=0.02, d_fine=0.001, d_coarse=0.0025, n_geom=6):
    """Delta/D values: d_fine/2^n_geom, ..., d_fine/2 (geometric start, so that the trapezoidal
    plate work is accurate where P(Delta) ~ Delta/ln(1/Delta) is most curved), then steps of
    d_fine up to fine_until, then steps of d_coarse up to dmax."""
    vals = [d_fine / 2 ** k for k in range(n_geom, 0, -1)]
    vals += list(np.arange(d_fine, fine_until + 1e-12, d_fine))
    x = fine_until
    while x < dmax - 1e-12:
        x = round(x + d_coarse, 10)
        vals.append(x)
    return [round(v, 10) for v in vals]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lam", type=float, required=True, help="lambda [Pa]")
    ap.add_argument("--mu", type=float, default=1.5e6, help="mu [Pa]")
    ap.add_argument("--R", type=float, default=1e-3, help="radius [m]")
    ap.add_argument("--level", type=int, default=2, help="mesh level (sizes halve per level)")
    ap.add_argument("--qdeg", type=int, default=4, help="quadrature degree")
    ap.add_argument("--displacement-only", action="store_true",
                    help="pure P2 displacement formulation even for lambda > 0")
    ap.add_argument("--small-strain", action="store_true",
                    help="linear elasticity (check against the linear Hertz solution only)")
    ap.add_argument("--dmax", type=float, default=0.40, help="final Delta/D")
    ap.add_argument("--d-fine", type=float, default=0.001, help="Delta/D step up to 0.02")
    ap.add_argument("--d-coarse", type=float, default=0.0025, help="Delta/D step after 0.02")
    ap.add_argument("--out", required=True, help="output CSV (all increments)")
    ap.add_argument("--verbose", action="store_true")
    args = ap.parse_args()

    t0 = time.time()
    err = check_constitutive(args.mu, max(args.lam, 3e6))
    assert err < 1e-6, err
    R, mu, lam = args.R, args.mu, args.lam
    mp = mesh_parameters(args.level, R)
    mesh = build_mesh(R, **mp)
    mixed = (lam > 0) and not args.displacement_only
    prob = SqueezedDisk(mesh, R, mu, lam, qdeg=args.qdeg, mixed=mixed,
                        small_strain=args.small_strain)
    print(f"# lambda = {lam:g} Pa, mu = {mu:g} Pa, R = {R:g} m, level {args.level}: "
          f"{mesh.num_cells()} triangles, {mesh.num_vertices()} vertices, {prob.ndofs} dofs, "
          f"{'P2-P1 mixed' if mixed else 'P2'}{', SMALL STRAIN' if args.small_strain else ''}, {len(prob.cy)} contact candidate nodes, "
          f"hc = {mp['hc']:.3e} m; constitutive FD check {err:.1e}", flush=True)
    D = 2 * R
    path = load_path(args.dmax, d_fine=args.d_fine, d_coarse=args.d_coarse)
    rows = []
    prev = (0.0, 0.0)  # (Delta, P)
    work = 0.0
    cur = 0.0
    targets = list(path)
    while targets:
        tgt = targets[0]
        w_save = prob.w.vector().copy()
        act_save = prob.active.copy()
        ok, its = prob.solve(tgt * D, verbose=args.verbose)
        if not ok:
            prob.w.vector()[:] = w_save
            prob.active = act_save
            mid = round(0.5 * (cur + tgt), 12)
            if tgt - cur < 1e-6:
                sys.exit(f"no convergence at Delta/D = {tgt}")
            print(f"  cut step: {cur} -> {mid}", flush=True)
            targets.insert(0, mid)
            continue
        targets.pop(0)
        cur = tgt
        o = prob.outputs(tgt * D)
        Dl = tgt * D
        work += 0.5 * (o["P"] + prev[1]) * (Dl - prev[0])
        prev = (Dl, o["P"])
        o.update(delta_over_D=tgt, work=work, its=its)
        rows.append(o)
        print(f"  D/D={tgt:.4f} P={o['P']:.6e} (sym {o['P_sym']:.6e}) a={o['a']:.5e} "
              f"a_node={o['a_node']:.5e} E={o['E']:.6e} W={work:.6e} "
              f"Pi={o['Pi']:.6e} pen/Delta={o['penetration'] / Dl:.1e} "
              f"nact={o['n_active']} th={o['theta_ref_deg']:.1f} its={its} t={time.time() - t0:.0f}s", flush=True)
    with open(args.out, "w") as fh:
        fh.write(f"# squeezed_disk_fenics.py lambda={lam:g} mu={mu:g} R={R:g} level={args.level} "
                 f"triangles={mesh.num_cells()} dofs={prob.ndofs} "
                 f"{'P2-P1' if mixed else 'P2'}{' small-strain' if args.small_strain else ''} qdeg={args.qdeg} hc={mp['hc']:.4e} "
                 f"runtime_s={time.time() - t0:.0f}\n")
        cols = ["delta_over_D", "P", "P_sym", "a", "a_node", "a_ref", "E", "work", "Pi", "area",
                "penetration", "n_active", "theta_ref_deg", "its"]
        fh.write(",".join(cols) + "\n")
        for o in rows:
            fh.write(",".join(f"{o[c]:.10g}" for c in cols) + "\n")
    print(f"# done in {time.time() - t0:.1f} s", flush=True)


if __name__ == "__main__":
    main()
