#!/usr/bin/python3
"""Contact force versus centre distance / D for the two gap criteria (docs/contact_gap.md).

Reads the CSV written by test_verification_contact_gap (default: $TMPDIR/mpmcd_contact_gap.csv;
columns criterion, shape, cells_per_diameter, h, diameter, distance, gap, force, active) and draws
docs/figures/contact_gap.png: one panel per resolution, one curve per criterion and shape.
Usage: /usr/bin/python3 tools/plot_contact_gap.py [CSV] [PNG]
"""
import csv
import os
import sys
import tempfile
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    src = sys.argv[1] if len(sys.argv) > 1 else os.path.join(tempfile.gettempdir(),
                                                             "mpmcd_contact_gap.csv")
    out = sys.argv[2] if len(sys.argv) > 2 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "docs", "figures", "contact_gap.png")
    runs = defaultdict(list)
    with open(src, newline="") as f:
        for row in csv.DictReader(f):
            key = (int(row["cells_per_diameter"]), row["criterion"], row["shape"])
            runs[key].append(row)
    resolutions = sorted({k[0] for k in runs})
    fig, axes = plt.subplots(1, len(resolutions), figsize=(5.5 * len(resolutions), 4.2),
                             squeeze=False)
    styles = {("gap", "linear"): ("C0", "-"), ("overlap", "linear"): ("C3", "-"),
              ("gap", "ugimp"): ("C0", "--"), ("overlap", "ugimp"): ("C3", "--")}
    for ax, cpd in zip(axes[0], resolutions):
        for (c, crit, shape), rows in sorted(runs.items()):
            if c != cpd:
                continue
            d = float(rows[0]["diameter"])
            h = float(rows[0]["h"])
            # approach branch only (up to the largest force)
            forces = [float(r["force"]) for r in rows]
            last = max(range(len(forces)), key=forces.__getitem__)
            x = [float(r["distance"]) / d for r in rows[: last + 1]]
            color, ls = styles.get((crit, shape), ("k", ":"))
            ax.plot(x, forces[: last + 1], color=color, ls=ls, label=f"{crit}, {shape}")
        ax.axvline(1.0, color="k", lw=0.8, ls=":")
        ax.axvline(1.0 + h / d, color="0.6", lw=0.8, ls=":")
        ax.set_xlabel("centre distance / D")
        ax.set_ylabel("normal contact force [N/m]")
        ax.set_title(f"D/h = {cpd} (dotted: d = D and d = D + h)")
        ax.invert_xaxis()
        ax.legend()
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    fig.savefig(out, dpi=120)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
