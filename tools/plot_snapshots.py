#!/usr/bin/python3
"""Pictures like the paper's Figure 3: the grains of a run at chosen solid fractions Φ.

Usage: plot_snapshots.py <run-folder> --phi 0.78 0.9 0.97 [--field grain|pressure|J]
                         [-o out-folder] [--dots] [--squares] [--dpi 150] [--forces]
                         [--format png pdf svg]

For each Φ asked, takes the VTU snapshot of the run (series <name>.pvd) whose time is nearest to
the CSV row (<name>.csv, column phi) with the nearest Φ, and draws every material point as its
domain (its initial square, side sqrt(V0), mapped by the deformation gradient estimated from its
neighbours' motion since the first snapshot; --squares: a square of side sqrt(V)) so that grains
look filled, coloured by grain (shuffled
categorical colours) or by pressure [MPa]; the walls of input.toml are drawn as lines at that
time; --dots adds the material points as black dots (as in the paper). --forces draws the
contact-force network over the grains (runs with [output] grains = true: the snapshot's
<name>_forces_<n>.csv and <name>_grains_<n>.csv, docs/observables.md): a line between the
centroids of each pair of grains in contact (from the contact point to the centroid for a wall),
its width proportional to the normal force (the mean force draws 1.5 pt). Writes
<out>/snapshot_phi<Φ>_<field>[_forces].<format> for each --format (default png; pdf and svg are
vector) in <out> (default <run-folder>/snapshots) and prints what it took.
Needs numpy and matplotlib (/usr/bin/python3 on Debian 12); no ParaView.
"""
import argparse
import csv
import os
import re
import sys
import tomllib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection, PolyCollection  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from vtu_points import read_vtu  # noqa: E402


def fail(msg):
    sys.exit(f"plot_snapshots.py: {msg}")


def read_run(folder):
    """(input dict, CSV columns dict, [(time, vtu path)]) of an mpmcd output folder."""
    path = os.path.join(folder, "input.toml")
    if not os.path.isfile(path):
        fail(f"{path}: no input copy (expected the output folder of `mpmcd run`)")
    with open(path, "rb") as f:
        cfg = tomllib.load(f)
    name = cfg.get("simulation", {}).get("name", "mpmcd")
    csv_path = os.path.join(folder, name + ".csv")
    if not os.path.isfile(csv_path):
        fail(f"{csv_path}: no CSV time series")
    with open(csv_path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows or "phi" not in rows[0]:
        fail(f"{csv_path}: no column phi (the walls must form a box)")
    cols = {k: np.array([float(r[k]) for r in rows]) for k in ("time", "phi", "eps")}
    pvd = os.path.join(folder, name + ".pvd")
    if not os.path.isfile(pvd):
        fail(f"{pvd}: no VTU series (set [output] vtu = true)")
    series = [(float(t), os.path.join(folder, file)) for t, file in
              re.findall(r'timestep="([^"]+)"[^>]*file="([^"]+)"', open(pvd).read())]
    if not series:
        fail(f"{pvd}: no snapshots")
    return cfg, cols, series


def wall_segments(cfg, t):
    """Each wall as (point at time t, direction along the wall)."""
    out = []
    for w in cfg.get("walls", []):
        p = np.array(w["point"], float) + t * np.array(w.get("velocity", [0.0, 0.0]), float)
        n = np.array(w["normal"], float)
        n /= np.linalg.norm(n)
        out.append((p, np.array([-n[1], n[0]])))
    return out


def domains(xy, arr, first):
    """Corners (n, 4, 2) of each point's domain: the initial square (side sqrt(V0)) mapped by the
    point's deformation gradient, estimated by least squares from the motion of its neighbours
    in the same grain since the first snapshot `first` = (positions, arrays); a plain square of
    side sqrt(V) where that is not possible."""
    half = 0.5 * np.sqrt(arr["volume"]) * 1e3
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float)
    out = xy[:, None, :] + half[:, None, None] * corners[None, :, :]
    if first is None or len(first[0]) != len(xy):
        return out
    X = first[0][:, :2] * 1e3
    half0 = 0.5 * np.sqrt(first[1]["volume"]) * 1e3
    grain = arr["grain"].astype(int)
    for g in np.unique(grain):
        idx = np.flatnonzero(grain == g)
        if len(idx) < 3:
            continue
        dX = X[idx][None, :, :] - X[idx][:, None, :]  # (n, n, 2): X_j - X_i
        dx = xy[idx][None, :, :] - xy[idx][:, None, :]
        near = np.linalg.norm(dX, axis=2) < 3.1 * half0[idx][:, None]  # lattice neighbours
        A = np.einsum("ijk,ijl,ij->ikl", dx, dX, near)  # sum dx dX^T
        B = np.einsum("ijk,ijl,ij->ikl", dX, dX, near)  # sum dX dX^T
        ok = np.abs(np.linalg.det(B)) > 1e-6 * np.einsum("ikk->i", B) ** 2
        F = np.zeros_like(A)
        F[ok] = A[ok] @ np.linalg.inv(B[ok])
        quad = xy[idx][:, None, :] + np.einsum("ikl,jl->ijk", F, corners) * half0[idx][:, None, None]
        out[idx[ok]] = quad[ok]
    return out


def force_network(folder, name, vtu):
    """(segments [mm], normal forces [N/m]) of the snapshot `vtu`'s contact pairs, from its grains
    and forces CSVs; None when the run wrote none (no [output] grains = true)."""
    m = re.search(r"_(\d+)\.vtu$", vtu)
    if not m:
        return None
    gpath = os.path.join(folder, f"{name}_grains_{m.group(1)}.csv")
    fpath = os.path.join(folder, f"{name}_forces_{m.group(1)}.csv")
    if not (os.path.isfile(gpath) and os.path.isfile(fpath)):
        return None
    with open(gpath, newline="") as f:
        centre = {int(r["grain"]): (float(r["x"]) * 1e3, float(r["y"]) * 1e3)
                  for r in csv.DictReader(f)}
    segs, fn = [], []
    with open(fpath, newline="") as f:
        for r in csv.DictReader(f):
            a, b, force = int(r["a"]), int(r["b"]), float(r["fn"])
            if force <= 0 or b not in centre:
                continue
            start = centre[a] if a >= 0 else (float(r["px"]) * 1e3, float(r["py"]) * 1e3)
            segs.append((start, centre[b]))
            fn.append(force)
    return segs, np.array(fn)


def draw(vtu, t, cfg, field, dots, title, paths, dpi, first, forces=None):
    pts, arr = read_vtu(vtu)
    xy = pts[:, :2] * 1e3  # mm
    half = 0.5 * np.sqrt(arr["volume"]) * 1e3
    squares = domains(xy, arr, first)
    fig, ax = plt.subplots(figsize=(6.4, 6))
    if field == "grain":
        grain = arr["grain"].astype(int)
        palette = plt.get_cmap("tab20").colors
        perm = np.random.default_rng(1).permutation(max(grain.max() + 1, 1))
        colours = [palette[perm[g] % len(palette)] for g in grain]
        coll = PolyCollection(squares, facecolors=colours, edgecolors="none")
        ax.add_collection(coll)
    else:
        values = arr["pressure"] / 1e6 if field == "pressure" else arr[field]
        coll = PolyCollection(squares, array=values, cmap="viridis", edgecolors="none")
        ax.add_collection(coll)
        fig.colorbar(coll, ax=ax, shrink=0.8,
                     label="pressure −tr σ/3 [MPa]" if field == "pressure" else field)
    if dots:
        ax.plot(xy[:, 0], xy[:, 1], "k.", ms=0.8)
    if forces is not None and len(forces[1]):
        segs, fn = forces
        widths = np.clip(1.5 * fn / fn.mean(), 0.2, 8.0)
        ax.add_collection(LineCollection(segs, linewidths=widths, colors="firebrick", alpha=0.85,
                                         capstyle="round", zorder=3))
    lo, hi = xy.min(axis=0) - 2 * half.max(), xy.max(axis=0) + 2 * half.max()
    for p, d in wall_segments(cfg, t):
        p = p * 1e3
        span = 2 * np.linalg.norm(hi - lo) + np.linalg.norm(p)
        ax.plot([p[0] - span * d[0], p[0] + span * d[0]], [p[1] - span * d[1], p[1] + span * d[1]],
                "k-", lw=1.5)
        lo, hi = np.minimum(lo, p), np.maximum(hi, p)
    margin = 0.03 * (hi - lo).max()
    ax.set_xlim(lo[0] - margin, hi[0] + margin)
    ax.set_ylim(lo[1] - margin, hi[1] + margin)
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_title(title, fontsize=10)
    fig.tight_layout()
    for path in paths:
        fig.savefig(path, dpi=dpi)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("folder", help="output folder of `mpmcd run`")
    ap.add_argument("--phi", type=float, nargs="+", required=True, help="solid fractions wanted")
    ap.add_argument("--field", default="grain", choices=["grain", "pressure", "J"])
    ap.add_argument("-o", "--output", default=None, help="default <folder>/snapshots")
    ap.add_argument("--dots", action="store_true", help="draw the material points as dots")
    ap.add_argument("--dpi", type=int, default=150)
    ap.add_argument("--squares", action="store_true",
                    help="plain squares of side sqrt(V) instead of the deformed domains")
    ap.add_argument("--forces", action="store_true",
                    help="the contact-force network over the grains (needs [output] grains = true)")
    ap.add_argument("--format", nargs="+", default=["png"], choices=["png", "pdf", "svg"],
                    help="file formats (pdf and svg are vector)")
    args = ap.parse_args()
    cfg, cols, series = read_run(args.folder)
    out = args.output or os.path.join(args.folder, "snapshots")
    os.makedirs(out, exist_ok=True)
    times = np.array([t for t, _ in series])
    first = None if args.squares else read_vtu(series[0][1])
    lam = [m.get("lambda") for m in cfg.get("materials", [])]
    lam_text = f"λ = {lam[0] / 1e6:g} MPa, " if len(set(lam)) == 1 and lam[0] is not None else ""
    for target in args.phi:
        row = int(np.argmin(np.abs(cols["phi"] - target)))
        k = int(np.argmin(np.abs(times - cols["time"][row])))
        t, vtu = series[k]
        at = int(np.argmin(np.abs(cols["time"] - t)))  # CSV row of the snapshot
        phi, eps = cols["phi"][at], cols["eps"][at]
        forces = None
        if args.forces:
            forces = force_network(args.folder, cfg.get("simulation", {}).get("name", "mpmcd"), vtu)
            if forces is None:
                fail(f"--forces: no grains/forces CSV for {os.path.basename(vtu)} (run with "
                     "[output] grains = true)")
        stem = f"snapshot_phi{target:.3f}_{args.field}" + ("_forces" if args.forces else "")
        paths = [os.path.join(out, f"{stem}.{ext}") for ext in args.format]
        title = f"{lam_text}Φ = {phi:.3f}, ε = {eps:.3f}, t = {t:.4g} s"
        draw(vtu, t, cfg, args.field, args.dots, title, paths, args.dpi, first, forces)
        print(f"Φ = {target:g}: {os.path.basename(vtu)} (t = {t:.6g} s, Φ = {phi:.4f}, "
              f"ε = {eps:.4f}) -> {', '.join(paths)}")


if __name__ == "__main__":
    main()
