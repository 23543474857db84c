#!/usr/bin/env python3
"""tests/mpi: a numerical failure met by one rank only (docs/parallel.md "Errors",
docs/robustness.md). Two disks, one per rank; grain 1, on rank 1, is crushed so that J < 0 in
step 1 with no dt cut allowed. Checks: exit code 3; the diagnostic (J, grain 1, the checkpoint
of the last good step) printed once, by rank 0, with rank 1's grain and point; the last good state
and a loadable failure checkpoint on disk; resuming that checkpoint on 2 ranks and on 1 rank
meets the same failure (exit 3 again, no hang, no crash).
Usage: check_failure_mpi.py MPMCD_BINARY MPIEXEC INPUT WORKDIR"""
import os, shutil, subprocess, sys

binary, mpiexec, toml, work = sys.argv[1:5]
MPI = [mpiexec, "--oversubscribe", "--allow-run-as-root", "-np"]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
fail = []


def run(args, ranks):
    cmd = [binary, "run", *args, "-t", "1"]
    if ranks > 1:
        cmd = MPI + [str(ranks)] + cmd
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=120, cwd=work)
    return r.returncode, r.stdout + r.stderr


code, out = run([toml, "-o", "out"], 2)
ckpt = os.path.join(work, "out", "mpmcd_checkpoint_000000000.h5")
if code != 3:
    fail.append(f"2 ranks: exit {code}, expected 3")
for text, count in (("J = ", 1), ("grain 1, point 227", 1),
                    (f"checkpoint of the last good step: out/mpmcd_checkpoint_000000000.h5", 1)):
    if out.count(text) != count:
        fail.append(f"2 ranks: '{text}' printed {out.count(text)} times, expected {count}")
for f in ("mpmcd_last_good.vtu", "mpmcd_checkpoint_000000000.h5"):
    if not os.path.exists(os.path.join(work, "out", f)):
        fail.append(f"2 ranks: no {f}")
print(out.strip().splitlines()[-1] if code == 3 else out)
if os.path.exists(ckpt):
    for ranks in (2, 1):
        code_r, out_r = run(["--restart", ckpt, "-o", f"resumed_{ranks}"], ranks)
        if code_r != 3 or "J = " not in out_r:
            fail.append(f"resumed on {ranks} rank(s): exit {code_r}, expected 3 with J:\n{out_r}")
        else:
            print(f"resumed on {ranks} rank(s): the same failure, exit 3")
if fail:
    sys.exit("FAILED:\n  " + "\n  ".join(fail) + "\n" + out)
print("ok")
