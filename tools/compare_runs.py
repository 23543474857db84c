#!/usr/bin/env python3
"""Compare compaction runs with a reference run (docs/compaction.md, "Comparing two runs").

    tools/compare_runs.py REF.csv RUN.csv [RUN.csv ...] [--noise NOISE.csv ...]
        [--targets 0.86,0.89,0.92,0.95,0.97] [--window 0.01] [--eps-tol 0.005] [--sigma-tol 0.02]

Each CSV is the `<name>.csv` of an `mpmcd run` of a compaction (columns phi, eps,
sigma_bottom_over_Mp and the energy ledger's wall_*_work, energy_change, contact_dissipation,
transfer_dissipation, internal_dissipation). For each run and each packing fraction target:

- the strain eps = ln(h/h0) at that Phi, linearly interpolated at the first crossing;
- the wall stress sigma/M_p as its mean over the rows with Phi in [target - window, target +
  window] (capped at the largest Phi all runs reach): single rows of a few-hundred-grain packing
  scatter by several per cent with its rearrangements, so a comparison to 2 % needs means;
- their differences from the reference (eps absolute, sigma relative), the largest |d eps| over
  Phi in steps of 0.005 between the first target and the last, and the ledger (per cent of the
  walls' work) at the last target.

A run passes when every |d eps| <= eps-tol and every window's |d sigma| <= sigma-tol. --noise
names a run of the reference's input perturbed at round-off (e.g. a tighter tolerance): its
differences, printed first, are how far the rearrangements alone move the answers, which no
comparison can resolve; with several, the largest of their differences per target is the noise
floor, and each run is also said to be within it or not. Exit code: 0 when every run passes, 1 when one does not, 2 on bad input.
"""
import argparse
import csv
import math
import sys

LEDGER = ("energy_change", "contact_dissipation", "transfer_dissipation", "internal_dissipation")


class InputError(Exception):
    pass


def load(path):
    """The CSV's numeric columns as lists of floats (comment lines start with '#')."""
    try:
        with open(path, newline="") as f:
            rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    except OSError as e:
        raise InputError(f"{path}: cannot read ({e.strerror})")
    if len(rows) < 3:
        raise InputError(f"{path}: expected a header and at least two rows")
    head = rows[0]
    cols = {}
    for j, name in enumerate(head):
        try:
            cols[name] = [float(r[j]) for r in rows[1:]]
        except (ValueError, IndexError):
            continue
    for need in ("phi", "eps", "sigma_bottom_over_Mp"):
        if need not in cols:
            raise InputError(f"{path}: no column '{need}' (a compaction CSV of mpmcd run expected)")
    return cols


def eps_at(run, phi):
    """eps at the first crossing of Phi = phi (linear in Phi), or nan if never reached."""
    p, e = run["phi"], run["eps"]
    if p[0] >= phi:
        return e[0]
    for i in range(1, len(p)):
        if p[i] >= phi > p[i - 1]:
            if p[i] == p[i - 1]:
                return e[i]
            t = (phi - p[i - 1]) / (p[i] - p[i - 1])
            return e[i - 1] + t * (e[i] - e[i - 1])
    return math.nan


def sigma_mean(run, lo, hi):
    """Mean sigma/M_p over the rows with lo <= Phi <= hi (nan if none)."""
    vals = [s for p, s in zip(run["phi"], run["sigma_bottom_over_Mp"]) if lo <= p <= hi]
    return sum(vals) / len(vals) if vals else math.nan


def ledger(run, phi):
    """The ledger's terms in per cent of the walls' work at the first row with Phi >= phi."""
    work_cols = [k for k in run if k.startswith("wall_") and k.endswith("_work")]
    if not work_cols or any(k not in run for k in LEDGER):
        return None
    i = next((i for i, p in enumerate(run["phi"]) if p >= phi), len(run["phi"]) - 1)
    w = sum(run[k][i] for k in work_cols)
    return [100 * run[k][i] / w for k in LEDGER] if w != 0 else None


def compare(ref, run, targets, window, top):
    """Differences of `run` from `ref`: per target (d eps, d sigma / sigma) and max |d eps|."""
    rows = []
    for t in targets:
        e0, e1 = eps_at(ref, t), eps_at(run, t)
        lo, hi = t - window, min(t + window, top)
        s0, s1 = sigma_mean(ref, lo, hi), sigma_mean(run, lo, hi)
        rows.append((e1, e1 - e0, s1, s1 / s0 - 1 if s0 != 0 else math.nan))
    grid = [targets[0] + 0.005 * k for k in range(int((targets[-1] - targets[0]) / 0.005 + 1e-9) + 1)]
    worst = max(abs(eps_at(run, p) - eps_at(ref, p)) for p in grid)
    return rows, worst


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("ref")
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--noise", action="append", default=[],
                    help="the reference's input perturbed at round-off (may be repeated)")
    ap.add_argument("--targets", default="0.86,0.89,0.92,0.95,0.97")
    ap.add_argument("--window", type=float, default=0.01, help="half-width of the sigma means in Phi")
    ap.add_argument("--eps-tol", type=float, default=0.005)
    ap.add_argument("--sigma-tol", type=float, default=0.02)
    a = ap.parse_args(argv)
    try:
        targets = sorted(float(x) for x in a.targets.split(","))
    except ValueError:
        print(f"compare_runs: --targets: expected numbers separated by commas, got '{a.targets}'",
              file=sys.stderr)
        return 2
    if not targets or a.window <= 0:
        print("compare_runs: --targets must not be empty and --window must be > 0", file=sys.stderr)
        return 2
    try:
        ref = load(a.ref)
        runs = [(p, load(p)) for p in a.runs]
        noise = [(p, load(p)) for p in a.noise]
    except InputError as e:
        print(f"compare_runs: {e}", file=sys.stderr)
        return 2
    everyone = [ref] + [r for _, r in runs] + [r for _, r in noise]
    top = min(max(r["phi"]) for r in everyone)
    if top < targets[-1]:
        print(f"compare_runs: a run stops at Phi = {top:.4f}, below the last target "
              f"{targets[-1]}", file=sys.stderr)
        return 2
    head = " ".join(f"{t:>8.3f}" for t in targets)
    print(f"eps at Phi = {head}; sigma/M_p: means over Phi +- {a.window} (to at most {top:.4f})")

    def show(name, run, diffs):
        rows, worst = diffs if diffs else ([(eps_at(run, t), 0, sigma_mean(run, t - a.window, min(
            t + a.window, top)), 0) for t in targets], 0.0)
        led = ledger(run, targets[-1])
        print(f"{name}")
        print("  eps      " + " ".join(f"{r[0]:8.4f}" for r in rows))
        print("  sigma    " + " ".join(f"{r[2]:8.4f}" for r in rows))
        if diffs:
            print("  d eps    " + " ".join(f"{r[1]:+8.4f}" for r in rows) + f"   max |d eps| {worst:.4f}")
            print("  d sigma  " + " ".join(f"{100 * r[3]:+7.1f}%" for r in rows))
        if led:
            print("  ledger at Phi = {:.3f}: stored {:.1f} %, contact {:.1f} %, transfers {:.1f} %, "
                  "bulk {:.1f} % of the wall work".format(targets[-1], *led))
        return rows, worst

    show(f"reference {a.ref}", ref, None)
    floor = None  # per target: the largest |d eps| and |d sigma| of the noise runs; max |d eps|
    for path, run in noise:
        rows, worst = show(f"noise {path} (rearrangements alone)", run,
                           compare(ref, run, targets, a.window, top))
        here = ([abs(r[1]) for r in rows], [abs(r[3]) for r in rows], worst)
        floor = here if floor is None else ([max(x, y) for x, y in zip(floor[0], here[0])],
                                            [max(x, y) for x, y in zip(floor[1], here[1])],
                                            max(floor[2], here[2]))
    if floor:
        print("noise floor (largest over the noise runs)")
        print("  |d eps|  " + " ".join(f"{x:8.4f}" for x in floor[0]) + f"   max |d eps| {floor[2]:.4f}")
        print("  |d sigma|" + " ".join(f"{100 * x:7.1f}%" for x in floor[1]))
    failed = 0
    for path, run in runs:
        rows, worst = compare(ref, run, targets, a.window, top)
        show(path, run, (rows, worst))
        ok_e = worst <= a.eps_tol
        ok_s = all(abs(r[3]) <= a.sigma_tol for r in rows)
        verdict = "within" if ok_e and ok_s else "NOT within"
        print(f"  {verdict} {a.eps_tol} in eps ({'ok' if ok_e else 'no'}) and "
              f"{100 * a.sigma_tol:g} % in sigma ({'ok' if ok_s else 'no'})")
        if floor:
            in_e = worst <= floor[2]
            in_s = all(abs(r[3]) <= f for r, f in zip(rows, floor[1]))
            print(f"  {'within' if in_e and in_s else 'NOT within'} the noise floor "
                  f"(eps {'ok' if in_e else 'no'}, sigma {'ok' if in_s else 'no'})")
        failed += not (ok_e and ok_s)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
