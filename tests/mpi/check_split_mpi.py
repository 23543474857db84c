#!/usr/bin/env python3
"""tests/mpi: points split on their owner rank (docs/accuracy.md, "Point splitting"). Two blocks
stretched freely until all their 800 points have split once (1,600 points): on 2 ranks every CSV
and VTU file is byte-identical to 1 rank's, and a 2-rank run stopped after the split (step 60) and
restarted ends with the same bytes.
Usage: check_split_mpi.py MPMCD_BINARY MPIEXEC INPUT WORKDIR"""
import filecmp, os, re, subprocess, sys

binary, mpiexec, toml, work = sys.argv[1:5]
NAME = "split_mpi"


def run(ranks, args):
    cmd = [binary, "run", "-q", "-t", "1", *args]
    if ranks > 1:
        cmd = [mpiexec, "--oversubscribe", "--allow-run-as-root", "-np", str(ranks)] + cmd
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    if r.returncode not in (0, 4):
        sys.exit(f"{' '.join(cmd)}: exit {r.returncode}\n{r.stdout}\n{r.stderr}")
    return r


one, two, cut = (os.path.join(work, n) for n in ("np1", "np2", "np2_restart"))
run(1, [toml, "-o", one, "--overwrite"])
run(2, [toml, "-o", two, "--overwrite"])
run(2, [toml, "-o", cut, "--overwrite", "--stop-after", "60"])
run(2, ["--restart", os.path.join(cut, f"{NAME}_checkpoint_000000060.h5")])

fail = []
last = os.path.join(one, f"{NAME}_000003.vtu")
with open(last, "rb") as f:  # appended binary data follows the XML header
    points = re.search(rb'NumberOfPoints="(\d+)"', f.read())
count = int(points.group(1)) if points else -1
print(f"points at the end: {count} (800 seeded)")
if count != 1600:
    fail.append("the 800 points did not all split once")
files = [f for f in sorted(os.listdir(one))
         if f.endswith((".csv", ".vtu", ".pvd")) and not f.endswith("_timers.csv")]
for f in files:
    for other, what in ((two, "2 ranks"), (cut, "the 2-rank restart")):
        if not filecmp.cmp(os.path.join(one, f), os.path.join(other, f), shallow=False):
            fail.append(f"{f}: {what} differs from 1 rank")
print(f"{len(files)} files compared")
if fail:
    sys.exit("\n".join(fail))
print("same bytes on 1 rank, 2 ranks and after a 2-rank restart")
