#!/usr/bin/env python3
"""tests/mpi: checkpoints of a 2-rank run (docs/parallel.md, docs/robustness.md).

1. A 2-rank run that re-deals its grains at every 50-step check, stopped with --stop-after at a
   step that is not a multiple of 50 and restarted on 2 ranks, ends bitwise identical to the
   uninterrupted run: every CSV, VTU and PVD file and the final checkpoint's bytes (so the
   distribution, the re-balancing counts and every rank's warm-start impulses were saved). The
   same stopped at step 200, in the step of a re-balancing that moves grains.
2. The same checkpoint restarted on 1 rank gives the observables of the 2-rank run within the
   contact tolerance.
3. SIGTERM to mpirun mid-run: every rank stops after the same step, one checkpoint is written,
   and the run resumes from it to the end with the final row of an uninterrupted run.
Usage: check_restart_mpi.py MPMCD_BINARY MPIEXEC INPUT WORKDIR"""
import csv, filecmp, glob, os, re, shutil, signal, subprocess, sys, time

binary, mpiexec, toml, work = sys.argv[1:5]
RTOL = 1e-6  # as tests/mpi/check_compaction_mpi.py
MPI = [mpiexec, "--oversubscribe", "--allow-run-as-root", "-np"]
REBALANCE = ["--rebalance", "1.000001"]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
fail = []


def run(args, ranks, expect=0):
    cmd = [binary, "run", *args, "-q", "-t", "1"]
    if ranks > 1:
        cmd = MPI + [str(ranks)] + cmd
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    if r.returncode != expect:
        sys.exit(f"{' '.join(cmd)}: exit {r.returncode}, expected {expect}:\n{r.stdout}\n{r.stderr}")
    return r


def rows(folder):
    with open(os.path.join(folder, "compaction_mpi.csv")) as f:
        return list(csv.DictReader(f))


def checkpoints(folder):
    return sorted(glob.glob(os.path.join(folder, "compaction_mpi_checkpoint_*.h5")))


# 1. Stop at step 130 and restart on 2 ranks: bitwise.
full, part = os.path.join(work, "full"), os.path.join(work, "part")
run([toml, "-o", full, *REBALANCE], 2)
r = run([toml, "-o", part, "--stop-after", "130", *REBALANCE], 2, expect=4)
if r.stderr.count("resume with:") != 1:
    fail.append(f"the resume hint should be printed once (by rank 0):\n{r.stderr}")
ckpt = os.path.join(part, "compaction_mpi_checkpoint_000000130.h5")
if not os.path.exists(ckpt):
    sys.exit(f"no checkpoint at step 130: {os.listdir(part)}")
single = os.path.join(work, "single")
os.makedirs(single)
for f in (ckpt, os.path.join(part, "compaction_mpi.csv")):  # for step 2, before the restart
    shutil.copy(f, single)                                    # below prunes or extends them
run(["--restart", ckpt, *REBALANCE], 2)
compared = 0
for f in sorted(os.listdir(full)):
    if f.endswith((".csv", ".vtu", ".pvd", ".h5")) and not f.endswith("_timers.csv"):
        compared += 1
        other = os.path.join(part, f)
        if not os.path.exists(other):
            fail.append(f"restarted run lacks {f}")
        elif not filecmp.cmp(os.path.join(full, f), other, shallow=False):
            fail.append(f"restarted 2-rank run differs in {f}")
print(f"2 ranks, stopped at step 130 and restarted: {compared} files compared")

# 1b. Stopped at step 200, in the step of a re-balancing that moves grains (their nodes'
# contacts change rank; every rank then holds every warm-start impulse): bitwise too.
part200 = os.path.join(work, "part200")
run([toml, "-o", part200, "--stop-after", "200", *REBALANCE], 2, expect=4)
run(["--restart", os.path.join(part200, "compaction_mpi_checkpoint_000000200.h5"), *REBALANCE], 2)
for f in ("compaction_mpi.csv", os.path.basename(checkpoints(full)[-1])):  # the end's
    if not filecmp.cmp(os.path.join(full, f), os.path.join(part200, f), shallow=False):
        fail.append(f"restarted at a re-balancing step: {f} differs")

# 2. The 2-rank checkpoint on 1 rank.
run(["--restart", os.path.join(single, os.path.basename(ckpt))], 1)
ref, one = rows(full), rows(single)
if len(ref) != len(one):
    fail.append(f"1-rank restart: {len(one)} rows, 2-rank run {len(ref)}")
worst = 0.0
for a, b in zip(ref, one):
    for key in ("phi", "eps", "ln_Vs_Vs0", "wall_top_stress", "wall_bottom_stress", "Z"):
        x, y = float(a[key]), float(b[key])
        scale = max(abs(x), abs(y))
        if scale > 0:
            worst = max(worst, abs(x - y) / scale)
print(f"2-rank checkpoint restarted on 1 rank: largest relative difference {worst:.3e}")
if worst > RTOL:
    fail.append(f"1-rank restart differs by {worst:.3e} > {RTOL}")

# 3. SIGTERM to mpirun.
longer = os.path.join(work, "longer.toml")
text = open(toml).read()
text = re.sub(r"(?m)^end_time = .*$", "end_time = 3e-4", text)
text = text.replace('file = "packing.csv"',
                    f'file = "{os.path.join(os.path.dirname(toml), "packing.csv")}"')
open(longer, "w").write(text)
ref_dir, sig_dir = os.path.join(work, "ref_long"), os.path.join(work, "sig")
run([longer, "-o", ref_dir], 2)
proc = subprocess.Popen(MPI + ["2", binary, "run", longer, "-q", "-t", "1", "-o", sig_dir],
                        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
deadline = time.time() + 120
csv_path = os.path.join(sig_dir, "compaction_mpi.csv")
while time.time() < deadline and proc.poll() is None:
    if os.path.exists(csv_path) and sum(1 for _ in open(csv_path)) > 5:
        break
    time.sleep(0.05)
proc.send_signal(signal.SIGTERM)
out, _ = proc.communicate(timeout=120)
saved = checkpoints(sig_dir)
if proc.returncode == 0 or len(saved) != 1 or "interrupted (SIGTERM)" not in out:
    fail.append(f"SIGTERM: exit {proc.returncode}, checkpoints {saved}, output:\n{out}")
else:
    step = int(re.search(r"_(\d+)\.h5$", saved[0]).group(1))
    print(f"SIGTERM: both ranks stopped after step {step}")
    run(["--restart", saved[0]], 2)
    a, b = rows(ref_dir)[-1], rows(sig_dir)[-1]
    if a != b:
        fail.append(f"resumed after SIGTERM, last row differs:\n{a}\n{b}")
if fail:
    sys.exit("FAILED:\n  " + "\n  ".join(fail))
print("ok")
