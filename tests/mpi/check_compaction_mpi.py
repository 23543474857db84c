#!/usr/bin/env python3
"""tests/mpi: the tiny compaction on 1 rank (no mpirun), 2 ranks twice (partition, default
re-balancing), 2 ranks keeping the first parts, 2 ranks (master), 2 ranks re-dealing the grains
every 50 steps. Checks: same observables (Phi, eps, wall stresses, contacts, Z) on 1 and 2 ranks
within the contact tolerance, and bitwise with the parts kept; 2-rank runs bitwise identical run
to run, the same files written, and the timer CSV with the serial fractions. Usage: check_compaction_mpi.py MPMCD_BINARY MPIEXEC INPUT WORKDIR"""
import csv, filecmp, os, subprocess, sys

binary, mpiexec, toml, work = sys.argv[1:5]
RTOL = 1e-6  # relative; the Gauss-Seidel tolerance is 1e-8 and the impulse tolerance 1e-6


def run(name, ranks, scheme="partition", extra=(), input_file=None):
    out = os.path.join(work, name)
    cmd = [binary, "run", input_file or toml, "-q", "-t", "1", "-o", out, "--overwrite", "--scheme",
           scheme, *extra]
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
fixed = run("np2_fixed", 2, extra=("--rebalance", "0"))
master = run("np2_master", 2, "master")
moving = run("np2_rebalance", 2, extra=("--rebalance", "1.000001"))  # re-deals every 50 steps
ref = rows(serial)
fail = []
for name, folder in [("2 ranks", two_a), ("2 ranks parts kept", fixed),
                     ("2 ranks master", master), ("2 ranks re-balanced", moving)]:
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
    # With the parts kept every contact and grain sees the serial values in the serial order.
    if folder in (fixed, master) and worst != 0.0:
        fail.append(f"{name}: relative difference {worst:.3e}, expected bitwise identity")
# Bitwise reproducible for a given rank count, and the same files for any rank count.
for f in sorted(os.listdir(two_a)):
    if f.endswith((".csv", ".vtu", ".pvd")) and not f.endswith("_timers.csv"):
        if not filecmp.cmp(os.path.join(two_a, f), os.path.join(two_b, f), shallow=False):
            fail.append(f"2-rank runs differ in {f}")
if sorted(os.listdir(two_a)) != sorted(os.listdir(serial)):
    fail.append(f"files differ: {sorted(os.listdir(two_a))} vs {sorted(os.listdir(serial))}")
# [stop] reached mid-run (Phi goes from 0.592 to 0.671): on 2 ranks the grains' areas are summed
# per grain over the ranks, not gathered; the run must stop after the same step with the same rows.
src = open(toml).read()
assert "phi = 0.95" in src and 'file = "packing.csv"' in src
packing = os.path.join(os.path.dirname(os.path.abspath(toml)), "packing.csv")
stop_toml = os.path.join(work, "compaction_mpi_stop.toml")
with open(stop_toml, "w") as f:
    f.write(src.replace("phi = 0.95", "phi = 0.65").replace('"packing.csv"', f'"{packing}"'))
stop1 = run("stop_np1", 1, input_file=stop_toml)
stop2 = run("stop_np2", 2, extra=("--rebalance", "0"), input_file=stop_toml)
rows1, rows2 = rows(stop1), rows(stop2)
if not rows1 or float(rows1[-1]["phi"]) < 0.65 or len(rows1) >= len(ref):
    fail.append(f"[stop] phi = 0.65 not reached mid-run on 1 rank ({len(rows1)} rows)")
if not filecmp.cmp(os.path.join(stop1, "compaction_mpi.csv"),
                   os.path.join(stop2, "compaction_mpi.csv"), shallow=False):
    fail.append("[stop] on 2 ranks: CSV differs from 1 rank")
else:
    print(f"[stop] phi = 0.65: both stop at step {rows1[-1]['step']}, Phi = {rows1[-1]['phi']}")
timers = open(os.path.join(two_a, "compaction_mpi_timers.csv")).read()
for key in ("p2g", "newton.solve", "contact.solve", "comm.entries", "one_rank_serial_fraction",
            "bytes_sent_per_rank_per_step", "# ranks,2", "# solo_s_at,solver.cpp:"):
    if key not in timers:
        fail.append(f"timers CSV lacks {key}")
# The per-synchronisation measure: both ranks made the same sequence of synchronisations (the
# same code lines), and each serial fraction is a fraction.
rows = dict(line[2:].split(",", 1) for line in timers.splitlines() if line.startswith("# "))
if rows.get("syncs_consistent") != "1" or int(rows.get("syncs", "0")) < 320:
    fail.append(f"synchronisations: {rows.get('syncs')}, consistent {rows.get('syncs_consistent')}")
for key in ("one_rank_serial_fraction", "one_rank_serial_fraction_cpu", "counted_serial_fraction",
            "stage_imbalance_fraction", "sync_wait_fraction"):
    v = float(rows.get(key, "nan"))
    if not 0 <= v <= 1:
        fail.append(f"{key} = {v}, not in [0, 1]")
# Counted in deterministic units: the same in the two identical 2-rank runs, to the last digit.
other = open(os.path.join(two_b, "compaction_mpi_timers.csv")).read()
rows_b = dict(line[2:].split(",", 1) for line in other.splitlines() if line.startswith("# "))
if rows.get("counted_serial_fraction") != rows_b.get("counted_serial_fraction"):
    fail.append("counted serial fraction differs between identical runs: "
                f"{rows.get('counted_serial_fraction')} vs {rows_b.get('counted_serial_fraction')}")
print(f"2 ranks: serial fraction {rows['one_rank_serial_fraction']} (wall), "
      f"{rows['counted_serial_fraction']} (counted), {rows['syncs']} synchronisations")
if fail:
    sys.exit("FAILED:\n  " + "\n  ".join(fail))
print("ok")
