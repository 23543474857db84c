#!/usr/bin/env python3
"""tests/mpi: a 3D run (two spheres colliding) on 1 rank and on 2 ranks: the same rows, the
observables within the contact tolerance, the same files; a 2-rank run stopped after 30 steps and
restarted on 2 ranks ends with the same CSV and VTU bytes as the uninterrupted 2-rank run.
Usage: check_three_d_mpi.py MPMCD_BINARY MPIEXEC INPUT WORKDIR"""
import csv, filecmp, os, subprocess, sys

binary, mpiexec, toml, work = sys.argv[1:5]
RTOL = 1e-6  # relative; the Gauss-Seidel tolerance is 1e-8 and the impulse tolerance 1e-6
NAME = "three_d_mpi"


def run(ranks, args):
    cmd = [binary, "run", "-q", "-t", "1", *args]
    if ranks > 1:
        cmd = [mpiexec, "--oversubscribe", "--allow-run-as-root", "-np", str(ranks)] + cmd
    return subprocess.run(cmd, capture_output=True, text=True, timeout=120)


def ok(r, what):
    if r.returncode != 0:
        sys.exit(f"{what} failed ({r.returncode}):\n{r.stdout}\n{r.stderr}")


def rows(folder):
    with open(os.path.join(folder, NAME + ".csv")) as f:
        return list(csv.DictReader(f))


serial, two, split = (os.path.join(work, n) for n in ("np1", "np2", "np2_split"))
ok(run(1, [toml, "-o", serial, "--overwrite"]), "1 rank")
ok(run(2, [toml, "-o", two, "--overwrite"]), "2 ranks")
r = run(2, [toml, "-o", split, "--overwrite", "--stop-after", "30"])
if r.returncode != 4:
    sys.exit(f"2 ranks --stop-after 30: exit {r.returncode}, expected 4:\n{r.stdout}\n{r.stderr}")
ok(run(2, ["--restart", os.path.join(split, f"{NAME}_checkpoint_000000030.h5")]), "2-rank restart")

fail = []
ref, other = rows(serial), rows(two)
if len(ref) != len(other):
    fail.append(f"2 ranks: {len(other)} rows, 1 rank {len(ref)}")
worst = 0.0
for a, b in zip(ref, other):
    for key in ("kinetic_energy", "elastic_energy", "momentum_x", "momentum_y", "momentum_z"):
        x, y = float(a[key]), float(b[key])
        scale = max(abs(x), abs(y), 1e-30)
        worst = max(worst, abs(x - y) / scale if scale > 1e-15 else 0.0)
print(f"2 ranks: {len(other)} rows, largest relative difference to 1 rank {worst:.3e}")
if worst > RTOL:
    fail.append(f"2 ranks: relative difference {worst:.3e} > {RTOL}")
if max(int(x["active_contacts"]) for x in ref) == 0:
    fail.append("the spheres never touched")
files = 0
for f in sorted(os.listdir(two)):
    if f.endswith((".csv", ".vtu", ".pvd")) and not f.endswith("_timers.csv"):
        files += 1
        if not os.path.exists(os.path.join(serial, f)):
            fail.append(f"{f}: written on 2 ranks, not on 1")
        if not filecmp.cmp(os.path.join(two, f), os.path.join(split, f), shallow=False):
            fail.append(f"{f}: differs after the 2-rank restart")
print(f"2-rank restart: {files} files compared")
if files < 10:
    fail.append(f"only {files} output files")
if fail:
    sys.exit("FAILED:\n" + "\n".join(fail))
print("ok")
