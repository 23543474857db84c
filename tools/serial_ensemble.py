#!/usr/bin/python3
"""Serial fraction in seconds, with the machine's jitter averaged out (docs/parallel.md,
"Serial fraction over repeated runs").

The time in which one rank works alone is measured at every synchronisation k: with d_rk the
time rank r worked since its previous synchronisation, the last rank to arrive worked alone for
max_r d_rk - (second largest d_rk) (parallel::Comm). On a machine whose speed jitters (the same
work takes +-10 % from one step to the next on a shared VM), a single run adds the jitter to that
figure: two ranks doing identical work show 10 % of a step "alone".

The parallel runs are bitwise reproducible for a rank count, so every run of the same
configuration makes the same synchronisations with the same work (this script checks it on the
counted units of every synchronisation). Averaging each synchronisation's intervals over R runs
keeps the scheme's own imbalance and divides the jitter by about sqrt(R):
  solo(R) = sum_k [max_r mean_R d_rk - second largest mean_R d_rk].
For two ranks |x| is convex, so by Jensen's inequality E[solo(R)] only falls as R grows, to the
scheme's own one-rank-alone time: each solo(R) is an upper bound of it (up to its own scatter).
The script runs R rounds of (partition, 2 ranks; mirror: 2 ranks with identical work, whose own
value is zero, so its solo(R) is the jitter left after R runs), and every fourth round the master
scheme and the one-rank step. It writes to the output folder
  ensemble_runs.csv    bench_parallel's row of every run
  ensemble.csv         config, R, solo time per step [ms] (wall and CPU time, mean over the
                       disjoint groups of R runs), as a fraction of the runs' total work
                       (sum over ranks and synchronisations of the mean intervals: the analogue of
                       the counted fraction's denominator) and of the one-rank step (Amdahl's f)
  ensemble_bounds.csv  config, R (every run), the upper bound above and a lower bound (cross-fit,
                       see crossfit()) in wall and CPU time, and the counted fraction [-]
  ensemble_sites.csv   config, code line, solo time per step at the largest R [ms]
  ensemble.png         the fractions against R, with the counted fraction and the 2 % target
Usage: tools/serial_ensemble.py [--build build/release] [--out ensemble_out] [--runs 32]
                                [--warmup 60] [--steps 200] [--rebalance 1.01]
                                [--rebalance-every 50] [--plot-only]"""
import argparse, csv, os, subprocess, sys
import numpy as np

ap = argparse.ArgumentParser()
ap.add_argument("--build", default="build/release")
ap.add_argument("--bench", help="bench_parallel (default: BUILD/bench/bench_parallel)")
ap.add_argument("--out", default="ensemble_out")
ap.add_argument("--runs", type=int, default=32, help="rounds (R at most)")
ap.add_argument("--warmup", type=int, default=60)
ap.add_argument("--steps", type=int, default=200)
ap.add_argument("--rebalance", type=float, default=1.01)
ap.add_argument("--rebalance-every", type=int, default=50)
ap.add_argument("--nice", type=int, default=10)
ap.add_argument("--configs", nargs="+", default=["partition", "mirror", "master", "serial"],
                help="what each round runs (master and serial every fourth round)")
ap.add_argument("--append", action="store_true", help="add rounds to the traces already there")
ap.add_argument("--plot-only", action="store_true", help="analyse the traces already there")
a = ap.parse_args()
os.makedirs(a.out, exist_ok=True)
bench = a.bench or os.path.join(a.build, "bench", "bench_parallel")
runs_csv = os.path.join(a.out, "ensemble_runs.csv")
CONFIGS = ("partition", "mirror", "master")


def trace_path(config, i):
    return os.path.join(a.out, f"trace_{config}_{i:03d}.csv")


def run(config, ranks, i):
    cmd = ["nice", "-n", str(a.nice)]
    if ranks > 1:
        cmd += ["mpirun", "--oversubscribe", "--allow-run-as-root", "--bind-to", "none",
                "-np", str(ranks)]
    scheme = "master" if config == "master" else "partition"
    cmd += [bench, "--scheme", scheme, "--threads", "1", "--warmup", str(a.warmup),
            "--steps", str(a.steps), "--csv", runs_csv]
    if ranks > 1:
        cmd += ["--trace", trace_path(config, i)]
    if config == "partition" and ranks > 1:
        cmd += ["--rebalance", str(a.rebalance), "--rebalance-every", str(a.rebalance_every)]
    if config == "mirror":
        cmd += ["--mirror", "1"]
    print(" ".join(cmd), flush=True)
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"failed: {r.stderr[-2000:]}")
    print(r.stdout.strip().splitlines()[-1][:120], flush=True)


if not a.plot_only:
    first = 0
    if a.append:  # continue the numbering of the traces already there
        first = 1 + max([int(f[-7:-4]) for f in os.listdir(a.out) if f.startswith("trace_")],
                        default=-1)
    else:
        for f in os.listdir(a.out):
            if f.startswith("trace_") or f == "ensemble_runs.csv":
                os.remove(os.path.join(a.out, f))
    for i in range(first, first + a.runs):
        for config in a.configs:
            if config in ("partition", "mirror") or i % 4 == 0:
                run(config, 1 if config == "serial" else 2, i)


def load(path):
    """Sites, wall (K, P), CPU (K, P) and units (K, P) of one trace."""
    with open(path) as f:
        rows = list(csv.reader(f))
    head, body = rows[0], rows[1:]
    p = sum(1 for h in head if h.startswith("wall_s"))
    vals = np.array([[float(x) for x in r[2:]] for r in body])
    return [r[1] for r in body], vals[:, :p], vals[:, p:2 * p], vals[:, 2 * p:]


def solo(d):
    """Sum over synchronisations of the largest minus the second largest interval (K, P)."""
    s = np.sort(d, axis=1)
    return float(np.sum(s[:, -1] - s[:, -2]))


def crossfit(d, rng, splits=200):
    """Lower bound of the scheme's own sum_k |mu_k| (two ranks; d: (R, K, 2)): the runs split in
    two halves A and B at random, each synchronisation's slower rank taken from A and its lead
    measured on B (and the other way round). B is independent of A, so the expectation is
    sum_k mu_k E[sign(m_A,k)] <= sum_k |mu_k|, with no jitter added. Mean over `splits` random
    splits, and the scatter of a single split."""
    diff = d[:, :, 0] - d[:, :, 1]
    h = len(d) // 2
    vals = []
    for _ in range(splits):
        idx = rng.permutation(len(d))
        ma, mb = diff[idx[:h]].mean(axis=0), diff[idx[h:2 * h]].mean(axis=0)
        vals.append(0.5 * float(np.sum(np.sign(ma) * mb + np.sign(mb) * ma)))
    return float(np.mean(vals)), float(np.std(vals))


def solo_by_site(d, sites):
    s = np.sort(d, axis=1)
    out = {}
    for site, x in zip(sites, s[:, -1] - s[:, -2]):
        out[site] = out.get(site, 0.0) + float(x)
    return out


with open(runs_csv) as f:
    run_rows = list(csv.DictReader(f))
serial_ms = float(np.median([float(r["step_ms"]) for r in run_rows if r["ranks"] == "1"]))
counted = {}
for r in run_rows:
    if r["ranks"] == "2":
        counted.setdefault(r["scheme"], float(r["counted_serial_fraction"]))

table, sites_rows, bounds = [], [], []
rng = np.random.default_rng(1)
for config in CONFIGS:
    paths = sorted(p for p in os.listdir(a.out) if p.startswith(f"trace_{config}_"))
    if not paths:
        continue
    traces = [load(os.path.join(a.out, p)) for p in paths]
    sites, _, _, units = traces[0]
    same = all(t[0] == sites and np.array_equal(t[3], units) for t in traces)
    if not same:
        sys.exit(f"{config}: the runs did not make the same synchronisations with the same work")
    wall = np.stack([t[1] for t in traces])  # (R, K, P)
    cpu = np.stack([t[2] for t in traces])
    n = len(traces)
    total_ms = 1e3 * float(np.sum(wall.mean(axis=0))) / a.steps  # both ranks' work per step
    print(f"{config}: {n} runs, {len(sites)} synchronisations each, identical work in all")
    r = 1
    while r <= n:
        if 2 * r > n:
            r = n  # the last row uses every run
        groups = [slice(g * r, (g + 1) * r) for g in range(n // r)]
        w = np.mean([solo(wall[g].mean(axis=0)) for g in groups]) * 1e3 / a.steps
        c = np.mean([solo(cpu[g].mean(axis=0)) for g in groups]) * 1e3 / a.steps
        table.append(dict(config=config, runs=r, groups=len(groups), solo_ms=w, solo_cpu_ms=c,
                          fraction_of_work=w / total_ms, fraction_of_serial_step=w / serial_ms,
                          cpu_fraction_of_serial_step=c / serial_ms,
                          counted_fraction=counted.get(config, 0.0) if config != "mirror" else 0.0))
        print(f"  R = {r:3d}: one rank alone {w:.3f} ms/step = {100 * w / total_ms:.2f} % of the "
              f"work, {100 * w / serial_ms:.2f} % of the one-rank step (CPU time "
              f"{100 * c / serial_ms:.2f} %)")
        r *= 2
    if wall.shape[2] == 2 and n >= 4:
        lw, lw_sd = crossfit(wall, rng)
        lc, lc_sd = crossfit(cpu, rng)
        upper = table[-1]
        bounds.append(dict(config=config, runs=n,
                           upper_wall=upper["fraction_of_serial_step"],
                           lower_wall=1e3 * lw / a.steps / serial_ms,
                           lower_wall_split_sd=1e3 * lw_sd / a.steps / serial_ms,
                           upper_cpu=upper["cpu_fraction_of_serial_step"],
                           lower_cpu=1e3 * lc / a.steps / serial_ms,
                           lower_cpu_split_sd=1e3 * lc_sd / a.steps / serial_ms,
                           counted=upper["counted_fraction"]))
        b = bounds[-1]
        print(f"  bounds over {n} runs (% of the one-rank step): wall {100 * b['lower_wall']:.2f}"
              f" (single split +-{100 * b['lower_wall_split_sd']:.2f}) to "
              f"{100 * b['upper_wall']:.2f}, CPU time {100 * b['lower_cpu']:.2f} to "
              f"{100 * b['upper_cpu']:.2f}; counted {100 * b['counted']:.2f}")
    for site, x in sorted(solo_by_site(wall.mean(axis=0), sites).items(), key=lambda kv: -kv[1]):
        sites_rows.append(dict(config=config, site=site, solo_ms=1e3 * x / a.steps))

with open(os.path.join(a.out, "ensemble.csv"), "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=list(table[0]))
    w.writeheader()
    w.writerows(table)
if bounds:
    with open(os.path.join(a.out, "ensemble_bounds.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(bounds[0]))
        w.writeheader()
        w.writerows(bounds)
with open(os.path.join(a.out, "ensemble_sites.csv"), "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=["config", "site", "solo_ms"])
    w.writeheader()
    w.writerows(sites_rows)
print(f"one-rank step (median of {sum(1 for r in run_rows if r['ranks'] == '1')}): "
      f"{serial_ms:.2f} ms")

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

fig, ax = plt.subplots(figsize=(8.6, 4.6))
colors = {"partition": "tab:blue", "mirror": "tab:gray", "master": "tab:red"}
for config in CONFIGS:
    rows = [t for t in table if t["config"] == config]
    if not rows:
        continue
    rs = [t["runs"] for t in rows]
    ax.plot(rs, [100 * t["fraction_of_serial_step"] for t in rows], "o-", color=colors[config],
            label=f"{config}: wall time")
    ax.plot(rs, [100 * t["cpu_fraction_of_serial_step"] for t in rows], "s--",
            color=colors[config], alpha=0.6, label=f"{config}: CPU time")
    if config != "mirror":
        ax.axhline(100 * rows[0]["counted_fraction"], color=colors[config], ls=":",
                   label=f"{config}: counted")
    for b in (b for b in bounds if b["config"] == config and b["lower_wall"] > 0):
        ax.errorbar([b["runs"]], [100 * b["lower_wall"]], yerr=[100 * b["lower_wall_split_sd"]],
                    fmt="v", color=colors[config], label=f"{config}: lower bound (wall)")
        ax.errorbar([b["runs"] * 1.15], [100 * b["lower_cpu"]], yerr=[100 * b["lower_cpu_split_sd"]],
                    fmt="v", mfc="none", color=colors[config],
                    label=f"{config}: lower bound (CPU time)")
ax.axhline(2.0, color="k", lw=0.8, label="target 2 %")
ax.set_xscale("log", base=2)
ax.set_yscale("log")
ax.set_xlabel("runs averaged per synchronisation, R")
ax.set_ylabel("one rank alone / one-rank step [%]")
ax.set_title("Serial fraction, 2 ranks, 300-grain slice")
ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
ax.grid(True, which="both", alpha=0.3)
fig.tight_layout()
fig.savefig(os.path.join(a.out, "ensemble.png"), dpi=130)
print(f"wrote {a.out}/ensemble.csv{', ensemble_bounds.csv' if bounds else ''}, "
      "ensemble_sites.csv, ensemble.png")
