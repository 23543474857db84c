#!/usr/bin/env python3
"""tests/mpi: the tiny compaction on 1 rank (no mpirun), 2 ranks twice (partition) and 2 ranks
(master), 2 ranks re-dealing the grains every 50 steps. Checks: same observables (Phi, eps, wall stresses, contacts, Z) on 1 and 2 ranks within
the contact tolerance, 2-rank runs bitwise identical run to run, the same files written, and the
timer CSV. Usage: check_compaction_mpi.py MPMCD_BINARY MPIEXEC INPUT WORKDIR"""
import csv, filecmp, os, subprocess, sys

binary, mpiexec, toml, work = sys.argv[1:5]
RTOL = 1e-6  # relative; the Gauss-Seidel tolerance is 1e-8 and the impulse tolerance 1e-6


def run(name, ranks, scheme="partition", extra=()):
    out = os.path.join(work, name)
    cmd = [binary, "run", toml, "-q", "-t", "1", "-o", out, "--scheme", scheme, *extra]
    if ranks > 1:
        cmd = [mpiexec, "--oversubscribe", "--allow-run-as-root", "-np", str(ranks)] + cmd
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    if r.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed ({r.returncode}):\n{r.stdout}\n{r.stderr}")
    return out


def rows(folder):
    with open(os.path.join(folder, "compaction_mpi.csv")) as f:
        return list(csv.DictReader(f))


serial = run("np1", 1)
two_a = run("np2_a", 2)
two_b = run("np2_b", 2)
master = run("np2_master", 2, "master")
moving = run("np2_rebalance", 2, extra=("--rebalance", "1.000001"))  # re-deals every 50 steps
ref = rows(serial)
fail = []
for name, folder in [("2 ranks", two_a), ("2 ranks master", master),
                     ("2 ranks re-balanced", moving)]:
    other = rows(folder)
    if len(other) != len(ref):
        fail.append(f"{name}: {len(other)} rows, 1 rank {len(ref)}")
        continue
    worst = 0.0
    for a, b in zip(ref, other):
        for key in ("phi", "eps", "ln_Vs_Vs0", "wall_top_stress", "wall_bottom_stress",
                    "wall_left_stress", "wall_right_stress", "kinetic_energy", "Z"):
            x, y = float(a[key]), float(b[key])
            scale = max(abs(x), abs(y), 1e-30)
            worst = max(worst, abs(x - y) / scale if max(abs(x), abs(y)) > 1e-9 * scale else 0)
    print(f"{name}: largest relative difference to 1 rank {worst:.3e}")
    if worst > RTOL:
        fail.append(f"{name}: relative difference {worst:.3e} > {RTOL}")
# Bitwise reproducible for a given rank count, and the same files for any rank count.
for f in sorted(os.listdir(two_a)):
    if f.endswith((".csv", ".vtu", ".pvd")) and not f.endswith("_timers.csv"):
        if not filecmp.cmp(os.path.join(two_a, f), os.path.join(two_b, f), shallow=False):
            fail.append(f"2-rank runs differ in {f}")
if sorted(os.listdir(two_a)) != sorted(os.listdir(serial)):
    fail.append(f"files differ: {sorted(os.listdir(two_a))} vs {sorted(os.listdir(serial))}")
timers = open(os.path.join(two_a, "compaction_mpi_timers.csv")).read()
for key in ("p2g", "newton.solve", "contact.solve", "comm.entries", "one_rank_serial_fraction",
            "bytes_sent_per_rank_per_step", "# ranks,2"):
    if key not in timers:
        fail.append(f"timers CSV lacks {key}")
if fail:
    sys.exit("FAILED:\n  " + "\n  ".join(fail))
print("ok")
