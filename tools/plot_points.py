#!/usr/bin/python3
"""PNG picture of an mpmcd .vtu snapshot: material points coloured by a field (no ParaView needed).

Usage: plot_points.py snapshot.vtu out.png [--field pressure|grain|J|speed] [--grid h]
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from vtu_points import read_vtu  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("vtu")
    ap.add_argument("png")
    ap.add_argument("--field", default="pressure")
    ap.add_argument("--size", type=float, default=4.0, help="marker size [pt^2]")
    args = ap.parse_args()
    pts, arr = read_vtu(args.vtu)
    if args.field == "speed":
        values, label = np.linalg.norm(arr["velocity"], axis=1), "speed [m/s]"
    elif args.field == "pressure":
        values, label = arr["pressure"] / 1e6, "pressure [MPa]"
    else:
        values, label = arr[args.field], args.field
    fig, ax = plt.subplots(figsize=(6, 6))
    sc = ax.scatter(pts[:, 0] * 1e3, pts[:, 1] * 1e3, c=values, s=args.size,
                    cmap="tab20" if args.field == "grain" else "viridis", linewidths=0)
    fig.colorbar(sc, ax=ax, label=label, shrink=0.8)
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_title(os.path.basename(args.vtu))
    fig.tight_layout()
    fig.savefig(args.png, dpi=120)


if __name__ == "__main__":
    main()
