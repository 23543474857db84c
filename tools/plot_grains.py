#!/usr/bin/python3
"""Plots of the grain-scale analysis written by `mpmcd analyze` (docs/observables.md).

Usage: plot_grains.py <analysis-folder>
Reads what is there of phi_pressure.csv and pressure_law.csv (the pressure law Phi(P)),
fabric.csv (fabric anisotropy and Z versus Phi), force_distribution.csv and
pressure_distribution.csv (P(f/<f>) and P(P/<P>) at the chosen Phi), and writes pressure_law,
fabric and distributions as .png and .pdf; one colour per run.
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def read(path):
    if not os.path.isfile(path):
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def column(rows, name, keep=lambda r: True):
    return np.array([float(r[name]) if r[name] != "" else np.nan for r in rows if keep(r)])


def save(fig, folder, name):
    fig.tight_layout()
    for ext in ("png", "pdf"):
        fig.savefig(os.path.join(folder, f"{name}.{ext}"), dpi=150)
    plt.close(fig)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    folder = sys.argv[1]
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    law = read(os.path.join(folder, "pressure_law.csv"))
    phip = read(os.path.join(folder, "phi_pressure.csv"))
    runs = sorted({r["run"] for r in phip}, key=int)
    if runs and law:
        fig, ax = plt.subplots(figsize=(6, 4.5))
        for k, run in enumerate(runs):
            c = colours[k % len(colours)]
            mine = lambda r, run=run: r["run"] == run  # noqa: E731
            p = column(phip, "pressure", mine) / 1e3
            ax.plot(p, column(phip, "phi", mine), ".", ms=2.5, color=c, label=f"run {run}")
            for f in law:
                if f["run"] != run or f["determined"] != "1":
                    continue
                phi_j, phi_max, p0 = (float(f[k]) for k in ("phi_J", "phi_max", "P0"))
                grid = np.linspace(0, np.nanmax(p) * 1e3, 200)
                ax.plot(grid / 1e3, phi_max - (phi_max - phi_j) * np.exp(-grid / p0), "-",
                        color=c, lw=1.2,
                        label=f"Φmax = {phi_max:.4f}, P0 = {p0 / 1e3:.3g} kPa")
                ax.axhline(phi_max, color=c, lw=0.6, ls=":")
        ax.set_xlabel("P = −(σ̄xx + σ̄yy)/2 [kPa]")
        ax.set_ylabel("Φ")
        ax.set_title("Φ(P) = Φmax − (Φmax − ΦJ) exp(−P/P0)")
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
        save(fig, folder, "pressure_law")

    fabric = read(os.path.join(folder, "fabric.csv"))
    if fabric:
        fig, ax = plt.subplots(figsize=(6, 4.5))
        ax2 = ax.twinx()
        for k, run in enumerate(sorted({r["run"] for r in fabric}, key=int)):
            c = colours[k % len(colours)]
            mine = lambda r, run=run: r["run"] == run  # noqa: E731
            phi = column(fabric, "phi", mine)
            ax.plot(phi, column(fabric, "fabric_a", mine), "-", color=c, label=f"a, run {run}")
            ax2.plot(phi, column(fabric, "Z", mine), "--", color=c, label=f"Z, run {run}")
        ax.set_xlabel("Φ")
        ax.set_ylabel("fabric anisotropy a = 2(R1 − R2) (solid)")
        ax2.set_ylabel("Z, rattlers removed (dashed)")
        ax.set_title("Fabric anisotropy and coordination")
        ax.grid(alpha=0.3)
        save(fig, folder, "fabric")

    forces = read(os.path.join(folder, "force_distribution.csv"))
    pressures = read(os.path.join(folder, "pressure_distribution.csv"))
    if forces or pressures:
        fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
        for ax, rows, what in ((axes[0], forces, "f/⟨f⟩"), (axes[1], pressures, "P/⟨P⟩")):
            keys = sorted({(r["run"], r["phi"]) for r in rows}, key=lambda k: (int(k[0]), k[1]))
            for k, (run, phi) in enumerate(keys):
                mine = lambda r, run=run, phi=phi: r["run"] == run and r["phi"] == phi  # noqa
                mid = 0.5 * (column(rows, "bin_lo", mine) + column(rows, "bin_hi", mine))
                ax.semilogy(mid, np.where(column(rows, "density", mine) > 0,
                                          column(rows, "density", mine), np.nan),
                            "o-", ms=3, color=colours[k % len(colours)],
                            label=f"run {run}, Φ = {float(phi):.3f}")
            ax.set_xlabel(what)
            ax.set_ylabel(f"P({what})")
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7)
        axes[0].set_title("Normal forces between grains")
        axes[1].set_title("Grain pressures (rattlers removed)")
        save(fig, folder, "distributions")


if __name__ == "__main__":
    main()
