#!/usr/bin/python3
"""Driver: regenerates squeezed_disk_fe.csv and the verification figures.

Runs squeezed_disk_fenics.py (plane-strain Neo-Hookean disk, R = 1 mm, mu = 1.5 MPa, squeezed
between two rigid frictionless plates up to Delta/D = 0.40) for lambda = 0, 3e6, 100e6 Pa on the
mesh levels 1, 2, 3 (all element sizes halve per level; level 3 is the reference), plus a
small-strain (linear elastic) run on level 3 up to Delta/D = 0.02, two processes at a time, then
    * writes squeezed_disk_fe.csv (level 3, all load increments) and
      squeezed_disk_fe_full.csv (same, with diagnostics),
    * writes verification.txt: mesh convergence of P and a, comparison with the 2D Hertz
      solution (Johnson, Contact Mechanics, section 5.6), stored energy vs plate work.
Units: SI (Pa, m, N/m, J/m), per unit thickness, full disk.

    /usr/bin/python3 run_reference.py            # everything (about 15 min on 2 cores)
    /usr/bin/python3 run_reference.py --post     # only the post-processing of runs/
    /usr/bin/python3 run_reference.py --extra    # + extra checks in runs/extra (level 4, ...)
"""
import argparse
import math
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
RUNS = os.path.join(HERE, "runs")
LAMBDAS = [0.0, 3e6, 100e6]
MU = 1.5e6
R = 1e-3
LEVELS = [1, 2, 3]
REF_LEVEL = 3
DATE = "2026-11-24"
CHECK_POINTS = [0.05, 0.2, 0.4]
TABLE_POINTS = [0.01, 0.02, 0.05, 0.10, 0.15, 0.20, 0.25, 0.30, 0.35, 0.40]
HERTZ_POINTS = [0.005, 0.01, 0.015, 0.02]
CSV_MIN = 0.001   # smaller increments (geometric start of the load path) only in the _full.csv


# optional extra checks: name -> extra command-line arguments (coarser load path, path independent)
EXTRA_RUNS = {
    "lam0_L4_coarsepath": ["--lam", "0", "--level", "4"],
    "lam3e+06_L4_coarsepath": ["--lam", "3e6", "--level", "4"],
    "lam1e+08_L4_coarsepath": ["--lam", "100e6", "--level", "4"],
    "lam1e+08_L3_coarsepath": ["--lam", "100e6", "--level", "3"],
    "lam1e+08_L3_coarsepath_q6": ["--lam", "100e6", "--level", "3", "--qdeg", "6"],
    "lam3e+06_L3_coarsepath_P2only": ["--lam", "3e6", "--level", "3", "--displacement-only"],
}


def extra_job(name):
    out = os.path.join(RUNS, "extra", name + ".csv")
    cmd = [sys.executable, os.path.join(HERE, "squeezed_disk_fenics.py")] + EXTRA_RUNS[name] + [
        "--d-fine", "0.005", "--d-coarse", "0.01", "--out", out]
    t = time.time()
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    with open(out.replace(".csv", ".log"), "w") as log:
        rc = subprocess.call(cmd, stdout=log, stderr=subprocess.STDOUT, env=env)
    print(f"  extra/{name}: rc={rc}, {time.time() - t:.0f} s", flush=True)
    if rc:
        raise RuntimeError(f"{cmd} failed")


def run_name(lam, level, linear=False):
    return os.path.join(RUNS, f"lam{lam:g}_L{level}{'_linear' if linear else ''}.csv")


def job(lam, level, linear=False):
    out = run_name(lam, level, linear)
    cmd = [sys.executable, os.path.join(HERE, "squeezed_disk_fenics.py"), "--lam", repr(lam),
           "--mu", repr(MU), "--R", repr(R), "--level", str(level), "--out", out]
    if linear:
        cmd += ["--small-strain", "--dmax", "0.02"]
    t = time.time()
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    with open(out.replace(".csv", ".log"), "w") as log:
        rc = subprocess.call(cmd, stdout=log, stderr=subprocess.STDOUT, env=env)
    print(f"  {os.path.basename(out)}: rc={rc}, {time.time() - t:.0f} s", flush=True)
    if rc:
        raise RuntimeError(f"{cmd} failed, see {out.replace('.csv', '.log')}")


def load(path):
    with open(path) as fh:
        head = fh.readline().strip()
        cols = fh.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=2, ndmin=2)
    d = {c: data[:, i] for i, c in enumerate(cols)}
    d["_head"] = head
    return d


def at(d, key, x):
    i = np.nonzero(np.abs(d["delta_over_D"] - x) < 1e-9)[0]
    if len(i) != 1:
        raise KeyError(f"Delta/D = {x} not computed")
    return d[key][i[0]]


def estar(lam, mu):
    return 4 * mu * (lam + mu) / (lam + 2 * mu)


def hertz(Delta, lam, mu=MU, Rr=R):
    """2D Hertz (Johnson 5.6): a = 2 sqrt(P R/(pi E*)), Delta = 2P/(pi E*) (2 ln(4R/a) - 1)."""
    Es = estar(lam, mu)

    def delta_of(P):
        a = 2 * math.sqrt(P * Rr / (math.pi * Es))
        return 2 * P / (math.pi * Es) * (2 * math.log(4 * Rr / a) - 1)

    lo, hi = 1e-12, 1e6
    for _ in range(200):
        mid = math.sqrt(lo * hi)
        if delta_of(mid) < Delta:
            lo = mid
        else:
            hi = mid
    P = math.sqrt(lo * hi)
    return P, 2 * math.sqrt(P * Rr / (math.pi * Es))


def powerlaw_work(d):
    """int P dDelta with P = c Delta^beta on every increment (exact for a power law; a check of
    the trapezoidal rule where P(Delta) ~ Delta / ln(1/Delta) is curved, i.e. at small Delta)."""
    x = d["delta_over_D"] * 2 * R
    P = d["P"]
    out = np.zeros_like(x)
    acc, x1, P1 = 0.0, 0.0, 0.0
    for i in range(len(x)):
        if x1 == 0.0:
            acc += 0.5 * x[i] * P[i]
        else:
            b = math.log(P[i] / P1) / math.log(x[i] / x1)
            acc += (x[i] * P[i] - x1 * P1) / (b + 1.0)
        out[i] = acc
        x1, P1 = x[i], P[i]
    return out


def post():
    lines = []

    def say(s=""):
        print(s)
        lines.append(s)

    runs = {(lam, lv): load(run_name(lam, lv)) for lam in LAMBDAS for lv in LEVELS}
    lin = {lam: load(run_name(lam, REF_LEVEL, True)) for lam in LAMBDAS}
    say(f"Squeezed-disk FE reference, verification figures (generated {DATE} by run_reference.py)")
    say(f"R = {R} m, mu = {MU} Pa; force P and half-width a per unit thickness, full disk")
    say()
    say("Runs:")
    for (lam, lv), d in sorted(runs.items()):
        say("  " + d["_head"].lstrip("# "))
    for lam, d in sorted(lin.items()):
        say("  " + d["_head"].lstrip("# "))
    say()

    # 1. mesh convergence ---------------------------------------------------------------------
    say("1. Mesh convergence: P [N/m] and a [m] on levels 1, 2, 3 (element sizes halve per level)")
    say(f"   {'lambda':>8} {'D/D':>5} {'P L1':>12} {'P L2':>12} {'P L3':>12} {'dP 1-2':>9} "
        f"{'dP 2-3':>9} {'a L1':>11} {'a L2':>11} {'a L3':>11} {'da 2-3':>8}")
    worst = 0.0
    worst_a = 0.0
    for lam in LAMBDAS:
        for x in CHECK_POINTS + [0.001, 0.005, 0.01, 0.1, 0.3]:
            P = [at(runs[(lam, lv)], "P", x) for lv in LEVELS]
            a = [at(runs[(lam, lv)], "a", x) for lv in LEVELS]
            d12 = (P[1] - P[0]) / P[2]
            d23 = (P[2] - P[1]) / P[2]
            da = (a[2] - a[1]) / a[2]
            if x in CHECK_POINTS:
                worst = max(worst, abs(d23))
            if x >= 0.05:
                worst_a = max(worst_a, abs(da))
            say(f"   {lam:8.3g} {x:5.3f} {P[0]:12.6g} {P[1]:12.6g} {P[2]:12.6g} {100 * d12:+8.4f}% "
                f"{100 * d23:+8.4f}% {a[0]:11.5e} {a[1]:11.5e} {a[2]:11.5e} {100 * da:+7.3f}%")
    say(f"   max |P(L3) - P(L2)| / P(L3) at Delta/D = 0.05, 0.2, 0.4 over the three lambda: "
        f"{100 * worst:.4f} %  (required < 0.3 %)")
    say(f"   max |a(L3) - a(L2)| / a(L3) for Delta/D >= 0.05 (points above): {100 * worst_a:.3f} %")
    say()

    # 2. Hertz --------------------------------------------------------------------------------
    say("2. Small-strain check against 2D Hertz (Johnson 5.6): a = 2 sqrt(PR/(pi E*)),")
    say("   Delta = 2P/(pi E*) (2 ln(4R/a) - 1), E* = 4 mu (lambda+mu)/(lambda+2mu); Hertz P and a")
    say("   taken at the same Delta; FE = Neo-Hookean level 3, FE-lin = small-strain FE level 3")
    say("   (same mesh, same contact algorithm, linear elasticity: isolates the discretisation error).")
    say(f"   {'lambda':>8} {'D/D':>6} {'P Hertz':>11} {'P FE':>11} {'dP FE':>8} {'dP FE-lin':>9}")
    for lam in LAMBDAS:
        d = runs[(lam, REF_LEVEL)]
        dl = lin[lam]
        for x in HERTZ_POINTS:
            Ph, ah = hertz(x * 2 * R, lam)
            P, Pl = at(d, "P", x), at(dl, "P", x)
            say(f"   {lam:8.3g} {x:6.3f} {Ph:11.5g} {P:11.5g} {100 * (P / Ph - 1):+7.2f}% "
                f"{100 * (Pl / Ph - 1):+8.2f}%")
    say("   Half-width. Hertz a is a linear-theory (reference-configuration) quantity; the FE a of the")
    say("   CSV is measured in the deformed configuration, where the surface points have moved toward")
    say("   the axis by the half-space tangential displacement u_x(a) = -(1-2nu)(1+nu)P/(2E)")
    say("   = -(1-2nu) P/(4 mu) (Johnson eq. 2.25b with the whole load P inside x < a).")
    say("   a_ref = reference coordinate X of the contact edge; a_H,def = a_H - (1-2nu) P_H/(4 mu).")
    say(f"   {'lambda':>8} {'D/D':>6} {'a Hertz':>11} {'a_ref FE':>8} {'a_ref lin':>9} "
        f"{'a_H,def':>11} {'a FE':>11} {'vs a_H,def':>10} {'a lin':>8}")
    for lam in LAMBDAS:
        d = runs[(lam, REF_LEVEL)]
        dl = lin[lam]
        nu = lam / (2 * (lam + MU))
        for x in HERTZ_POINTS:
            Ph, ah = hertz(x * 2 * R, lam)
            ahd = ah - (1 - 2 * nu) * Ph / (4 * MU)
            a, al = at(d, "a", x), at(dl, "a", x)
            ar, arl = at(d, "a_ref", x), at(dl, "a_ref", x)
            say(f"   {lam:8.3g} {x:6.3f} {ah:11.4e} {100 * (ar / ah - 1):+7.2f}% "
                f"{100 * (arl / ah - 1):+8.2f}% {ahd:11.4e} {a:11.4e} {100 * (a / ahd - 1):+9.2f}% "
                f"{100 * (al / ahd - 1):+7.2f}%")
    say("   (percentages: relative difference to the Hertz value of the same column group; the node")
    say(f"   spacing along the arc on level 3 is R/400 = {R / 400:.1e} m)")
    say()

    # 3. energy -------------------------------------------------------------------------------
    say("3. Energy: stored energy E = 4 int W dA (level 3) vs plate work int P dDelta (trapezoid)")
    say("   (Pi = value of the mixed u-p functional, whose stationary point is computed)")
    say(f"   {'lambda':>8} {'D/D':>5} {'E [J/m]':>13} {'work [J/m]':>13} {'(E-W)/W':>9} "
        f"{'mixed Pi':>13}")
    worst_e = 0.0
    for lam in LAMBDAS:
        d = runs[(lam, REF_LEVEL)]
        rel = (d["E"] - d["work"]) / d["work"]
        sel = d["delta_over_D"] >= 0.01 - 1e-12
        worst_e = max(worst_e, np.abs(rel[sel]).max())
        for x in TABLE_POINTS:
            E, W, Pi = at(d, "E", x), at(d, "work", x), at(d, "Pi", x)
            say(f"   {lam:8.3g} {x:5.2f} {E:13.6e} {W:13.6e} {100 * (E / W - 1):+8.4f}% {Pi:13.6e}")
        msg = ", ".join(
            f">= {t:g}: {100 * np.abs(rel[d['delta_over_D'] >= t - 1e-12]).max():.3f} %"
            for t in [0.001, 0.002, 0.005, 0.01])
        say(f"   lambda = {lam:g}: max |E - W|/W over the increments with Delta/D {msg}")
        d["work_powerlaw"] = powerlaw_work(d)
        relp = (d["E"] - d["work_powerlaw"]) / d["work_powerlaw"]
        msg = ", ".join(
            f">= {t:g}: {100 * np.abs(relp[d['delta_over_D'] >= t - 1e-12]).max():.3f} %"
            for t in [0.001, 0.002, 0.005, 0.01])
        say(f"   {'':{len(f'lambda = {lam:g}')}}  same with the work integrated by piecewise power "
            f"laws: {msg}")
    say(f"   max over the three lambda (Delta/D >= 0.01): {100 * worst_e:.4f} % (required < 0.5 %)")
    say()
    say("4. Other checks (level 3): max penetration of an inactive node / Delta, |P_contact - "
        "P_symmetry-plane| / P")
    for lam in LAMBDAS:
        d = runs[(lam, REF_LEVEL)]
        Dl = d["delta_over_D"] * 2 * R
        say(f"   lambda = {lam:g}: penetration/Delta max {np.max(d['penetration'] / Dl):.1e}, "
            f"force balance {np.max(np.abs(d['P'] - d['P_sym']) / d['P']):.1e}, "
            f"area change at 0.40: {at(d, 'area', 0.4) / (math.pi * R * R) - 1:+.4%}, "
            f"outermost contact node at reference angle {at(d, 'theta_ref_deg', 0.4):.1f} deg")
    extra = os.path.join(RUNS, "extra")
    ex = {}
    for name in EXTRA_RUNS:
        p = os.path.join(extra, name + ".csv")
        if os.path.exists(p):
            ex[name] = load(p)
    if ex:
        say()
        say("5. Extra checks (run_reference.py --extra; load path Delta/D step 0.005 to 0.02, then 0.01):")
        say("   relative difference of P and a to the level-3 reference at the same Delta/D")
        for name, d in ex.items():
            lam = float(name.split("_")[0][3:])
            ref = runs[(lam, REF_LEVEL)]
            say("   " + d["_head"].lstrip("# "))
            for x in [0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.4]:
                say(f"      D/D = {x:4.2f}: P {at(d, 'P', x):11.6g} ({100 * (at(d, 'P', x) / at(ref, 'P', x) - 1):+.4f}%), "
                    f"a {at(d, 'a', x):.5e} ({100 * (at(d, 'a', x) / at(ref, 'a', x) - 1):+.3f}%), "
                    f"E {100 * (at(d, 'E', x) / at(ref, 'E', x) - 1):+.4f}%")
    with open(os.path.join(HERE, "verification.txt"), "w") as fh:
        fh.write("\n".join(lines) + "\n")

    # CSV -------------------------------------------------------------------------------------
    ref = {lam: runs[(lam, REF_LEVEL)] for lam in LAMBDAS}

    def field(d, key):
        return d["_head"].split(key + "=")[1].split()[0]

    tri_txt = field(ref[0.0], "triangles")
    dof_txt = {lam: field(ref[lam], "dofs") for lam in LAMBDAS}
    small_txt = ", ".join(
        f"{100 * max(abs(at(runs[(l, 3)], 'P', x) / at(runs[(l, 2)], 'P', x) - 1) for l in LAMBDAS):.2f} % "
        f"at {x:g}" for x in [0.001, 0.005, 0.01])
    head = [
        "# Finite-element reference: plane-strain compressible Neo-Hookean disk squeezed between two",
        "# rigid flat frictionless plates (quasi-static), full disk, per unit thickness, SI units.",
        "# W = mu/2 (tr C - 2) - mu ln J + lambda/2 (ln J)^2 (F33 = 1); delta_over_D = loss of diameter / D;",
        "# force = plate force; half_width = half-width of the flat contact zone (deformed configuration);",
        "# elastic_energy = int W dA over the reference disk; plate_work = int P dDelta (trapezoid over all",
        "# computed increments, including Delta/D = 0.001/64 ... 0.001/2 listed only in squeezed_disk_fe_full.csv).",
        f"# Generated {DATE} by tests/reference/squeezed_disk/run_reference.py + squeezed_disk_fenics.py",
        "# (FEniCS/dolfin 2019.2, gmsh 4.8), quarter disk with symmetry conditions, node-wise active-set",
        "# contact, Newton at every increment. Mesh: level 3, " + tri_txt + " triangles, element size",
        "# R/200 along the contact arc; P2 for lambda = 0 (" + dof_txt[0.0] + " dofs), Taylor-Hood P2-P1 for",
        "# lambda > 0 (" + dof_txt[3e6] + " dofs).",
        "# Small Delta/D: |P(level 3) - P(level 2)|/P = " + small_txt + " (max over lambda).",
        f"# Mesh convergence: max |P(level 3) - P(level 2)|/P at Delta/D = 0.05, 0.2, 0.4 over the three "
        f"lambda = {100 * worst:.3f} %;",
        f"# max |a(level 3) - a(level 2)|/a for Delta/D >= 0.05: {100 * worst_a:.2f} %; "
        f"max |energy - work|/work for Delta/D >= 0.01: {100 * worst_e:.3f} %.",
    ]
    with open(os.path.join(HERE, "squeezed_disk_fe.csv"), "w") as fh:
        fh.write("\n".join(head) + "\n")
        fh.write("lambda_Pa,mu_Pa,R_m,delta_over_D,force_N_per_m,half_width_m,"
                 "elastic_energy_J_per_m,plate_work_J_per_m\n")
        for lam in LAMBDAS:
            d = ref[lam]
            for i in range(len(d["delta_over_D"])):
                if d["delta_over_D"][i] < CSV_MIN - 1e-12:
                    continue
                fh.write(f"{lam:.7g},{MU:.7g},{R:.7g},{d['delta_over_D'][i]:.7g},{d['P'][i]:.7g},"
                         f"{d['a'][i]:.7g},{d['E'][i]:.7g},{d['work'][i]:.7g}\n")
    cols = ["delta_over_D", "P", "P_sym", "a", "a_node", "a_ref", "E", "work", "work_powerlaw", "Pi",
            "area", "penetration",
            "n_active", "theta_ref_deg", "its"]
    with open(os.path.join(HERE, "squeezed_disk_fe_full.csv"), "w") as fh:
        fh.write("# Same runs as squeezed_disk_fe.csv with diagnostics: P_sym = reaction on the plane Y = 0,\n"
                 "# a = interpolated half-width (used in squeezed_disk_fe.csv), a_node = x of the outermost\n"
                 "# contact node, a_ref = reference X of the contact edge, work_powerlaw = int P dDelta with\n"
                 "# P = c Delta^beta on every increment (work = trapezoid, used in squeezed_disk_fe.csv),\n"
                 "# Pi = mixed functional [J/m], area = deformed area [m^2], penetration = max\n"
                 "# penetration of a node [m], n_active = contact nodes of the quarter, theta_ref_deg =\n"
                 "# reference angle of the outermost contact node, its = Newton iterations.\n")
        fh.write("lambda_Pa," + ",".join(cols) + "\n")
        for lam in LAMBDAS:
            d = ref[lam]
            for i in range(len(d["delta_over_D"])):
                fh.write(f"{lam:.7g}," + ",".join(f"{d[c][i]:.9g}" for c in cols) + "\n")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--post", action="store_true", help="only post-process existing runs/")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--extra", action="store_true",
                    help="also run the extra checks (level 4 etc., about 40 min more on 2 cores)")
    args = ap.parse_args()
    if args.extra:
        os.makedirs(os.path.join(RUNS, "extra"), exist_ok=True)
        with ThreadPoolExecutor(args.jobs) as ex:
            for f in [ex.submit(extra_job, n) for n in EXTRA_RUNS]:
                f.result()
    if not args.post:
        os.makedirs(RUNS, exist_ok=True)
        t = time.time()
        jobs = [(lam, lv, False) for lv in sorted(LEVELS, reverse=True) for lam in LAMBDAS]
        jobs += [(lam, REF_LEVEL, True) for lam in LAMBDAS]
        with ThreadPoolExecutor(args.jobs) as ex:
            for f in [ex.submit(job, *j) for j in jobs]:
                f.result()
        print(f"all runs done in {time.time() - t:.0f} s")
    post()


if __name__ == "__main__":
    main()
