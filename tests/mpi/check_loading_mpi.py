#!/usr/bin/env python3
"""tests/mpi: wall loading ([loading], docs/loading.md) on 1 rank (no mpirun) and 2 ranks with the
parts kept (--rebalance 0): a stage that ends when Phi crosses 0.762 (Phi summed per grain over the
ranks), then four servo walls whose wall forces are summed over the ranks before every rank moves
the walls. Checks: both stages ran, the loading ended the run, and the CSV files are identical
byte for byte. Usage: check_loading_mpi.py MPMCD_BINARY MPIEXEC INPUT WORKDIR"""
import csv, filecmp, os, subprocess, sys

binary, mpiexec, toml, work = sys.argv[1:5]


def run(name, ranks):
    out = os.path.join(work, name)
    cmd = [binary, "run", toml, "-t", "1", "-o", out, "--overwrite", "--rebalance", "0"]
    if ranks > 1:
        cmd = [mpiexec, "--oversubscribe", "--allow-run-as-root", "-np", str(ranks)] + cmd
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    if r.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed ({r.returncode}):\n{r.stdout}\n{r.stderr}")
    return out, r.stdout + r.stderr


one, log1 = run("np1", 1)
two, log2 = run("np2", 2)
fail = []
for name, log in (("1 rank", log1), ("2 ranks", log2)):
    if "loading stage 1 ('approach') ended" not in log or "loading finished: loading stage 2" not in log:
        fail.append(f"{name}: the stages did not end as expected:\n{log}")
with open(os.path.join(one, "loading_mpi.csv")) as f:
    rows = list(csv.DictReader(f))
stages = sorted({r["stage"] for r in rows})
if stages != ["1", "2"]:
    fail.append(f"stages in the CSV: {stages}")
if not filecmp.cmp(os.path.join(one, "loading_mpi.csv"), os.path.join(two, "loading_mpi.csv"),
                   shallow=False):
    fail.append("the CSV on 2 ranks differs from 1 rank")
print(f"{len(rows)} rows, last: stage {rows[-1]['stage']}, phi {float(rows[-1]['phi']):.4f}, "
      f"top wall stress {float(rows[-1]['wall_top_stress']):.4g} Pa")
if fail:
    sys.exit("\n".join(fail))
print("loading on 1 and 2 ranks: identical CSV")
