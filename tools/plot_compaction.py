#!/usr/bin/python3
"""Plots of the paper's Figures 4 and 5 from the CSV files written by `mpmcd analyze`.

Usage: plot_compaction.py <analysis-folder>
Reads figure4.csv, figure5.csv and compaction_fit.csv there and writes figure4.png/.pdf (eps
and ln(Vs/Vs0) versus Phi) and figure5.png/.pdf (sigma/M_p of the bottom wall versus Phi with the
fitted eq. (10)); one colour per run, legend by lambda (docs/observables.md).

Eq. (10) takes the coordination number Z, which steps by 2/N as contacts open and close. The
curve is drawn with a smooth Z(Phi) fitted to the measured one beyond jamming,
Z = Z_J + b sqrt(Phi - Phi_J) (the square-root rise of Z above jamming, O'Hern et al., PRE 68,
011306, 2003), so the line shows the law and not the contact noise.
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def read(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return rows


def column(rows, name, run):
    return np.array([float(r[name]) if r[name] != "" else np.nan for r in rows if r["run"] == run])


def label_jamming(ax, fit, colour, k):
    """The jamming packing fraction of one run: a dotted vertical line, labelled Φ_J."""
    if not fit["phi_J"]:
        return
    phi_j = float(fit["phi_J"])
    ax.axvline(phi_j, color=colour, lw=0.6, ls=":")
    ax.annotate(rf"$\Phi_J$ = {phi_j:.3f}", xy=(phi_j, 0.5 - 0.06 * k),
                xycoords=("data", "axes fraction"), xytext=(3, 0), textcoords="offset points",
                color=colour, fontsize=7, va="center",
                bbox=dict(fc="white", ec="none", alpha=0.8, pad=1))


def smooth_z(phi, z, phi_j):
    """Least-squares Z_J, b of Z = Z_J + b sqrt(Phi - Phi_J) over the rows beyond jamming."""
    ok = np.isfinite(z) & (phi > phi_j)
    if ok.sum() < 3:
        return None
    a = np.column_stack([np.ones(ok.sum()), np.sqrt(phi[ok] - phi_j)])
    (z_j, b), *_ = np.linalg.lstsq(a, z[ok], rcond=None)
    return z_j, b


def compaction_law(phi, z, c1, c2, mp, kp):
    """Seed eq. (10): sigma/M_p = -Z Phi / (Z + M_p/(c1 K_p)) (ln Phi + c2)."""
    return -z * phi / (z + mp / (c1 * kp)) * (np.log(phi) + c2)


def save(fig, folder, name):
    """One figure as PNG (screen) and PDF (vector, for print)."""
    for ext in ("png", "pdf"):
        fig.savefig(os.path.join(folder, f"{name}.{ext}"), dpi=130)
    plt.close(fig)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    folder = sys.argv[1]
    fits = read(os.path.join(folder, "compaction_fit.csv"))
    fig4 = read(os.path.join(folder, "figure4.csv"))
    fig5 = read(os.path.join(folder, "figure5.csv"))
    lambdas = [float(f["lambda"]) for f in fits]
    labels = {}
    for f in fits:
        lam = float(f["lambda"])
        label = f"λ = {lam / 1e6:g} MPa"
        if lambdas.count(lam) > 1:
            label += f" ({os.path.basename(os.path.normpath(f['folder']))})"
        labels[f["run"]] = label
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]

    # Figure 4: eps (solid) and ln(Vs/Vs0) (dashed) versus Phi.
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for k, f in enumerate(fits):
        run, c = f["run"], colours[k % len(colours)]
        phi = column(fig4, "phi", run)
        ax.plot(phi, column(fig4, "eps", run), "-", color=c, label=f"ε, {labels[run]}")
        ax.plot(phi, column(fig4, "ln_Vs_Vs0", run), "--", color=c,
                label=f"ln(Vs/Vs0), {labels[run]}")
        label_jamming(ax, f, c, k)
    ax.set_xlabel("Φ")
    ax.set_ylabel("ε,  ln(Vs/Vs0)")
    ax.set_title("Vertical strain and grain volume change")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    save(fig, folder, "figure4")

    # Figure 5: sigma/M_p versus Phi, fitted eq. (10) as a line over the fitted range, with the
    # smooth Z(Phi) (smooth_z) when it can be fitted, else with the measured Z.
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for k, f in enumerate(fits):
        run, c = f["run"], colours[k % len(colours)]
        phi = column(fig5, "phi", run)
        y = column(fig5, "sigma_over_Mp", run)
        model = column(fig5, "model", run)
        ax.plot(phi, y, ".", ms=2.5, color=c, label=f"{labels[run]}")
        label_jamming(ax, f, c, k)
        if f["c1"]:
            ok = np.isfinite(model)
            label = (f"eq. (10): c1 = {float(f['c1']):.3g} ± {float(f['c1_error']):.1g}, "
                     f"c2 = {float(f['c2']):.3g} ± {float(f['c2_error']):.1g}")
            line = dict(color="k" if len(fits) == 1 else c, lw=1.2)
            zfit = smooth_z(phi, column(fig5, "Z", run), float(f["phi_J"]))
            if zfit is None:
                ax.plot(phi[ok], model[ok], "-", label=label, **line)
                continue
            grid = np.linspace(phi[ok].min(), phi[ok].max(), 400)
            z_j, b = zfit
            ax.plot(grid, compaction_law(grid, z_j + b * np.sqrt(grid - float(f["phi_J"])),
                                         float(f["c1"]), float(f["c2"]), float(f["Mp"]),
                                         float(f["Kp"])), "-",
                    label=f"{label}\n  with Z = {z_j:.2f} + {b:.2f} √(Φ − Φ_J)", **line)
    ax.set_xlabel("Φ")
    ax.set_ylabel("σ / M_p (bottom wall, < 0 in compression)")
    ax.set_title("Wall stress and the compaction law, eq. (10)")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    save(fig, folder, "figure5")


if __name__ == "__main__":
    main()
