#!/usr/bin/python3
"""Tests of tools/plot_snapshots.py (ctest unit/tools/PlotSnapshots).

Usage: test_plot_snapshots.py [workdir]

- a grain is drawn without gaps: a polar-seeded disk (the seeding of src/points/seeding.cpp, whose
  ring domains leave slivers between them) rasterised in each field: every pixel inside it has
  the grain's colour (no background, no seam);
- a concavity wider than a domain stays open (an annulus keeps its hole);
- neighbouring grains never share a colour: seven touching disks (a hexagon around one), pairs
  only in the contact list, and a wheel graph with a palette too small for it;
- the command end to end on a synthetic run folder (PNG, PDF, SVG, --forces; each field), and
  bad input: exit 2 with a message naming the file.
"""
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
TOOLS = os.path.join(HERE, "..", "..", "tools")
sys.path.insert(0, TOOLS)
import plot_snapshots as ps  # noqa: E402
from vtu_points import write_vtu  # noqa: E402

WORK = sys.argv.pop(1) if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="plot_snapshots_")


def polar_disk(centre, radius, n, first_ring=0):
    """(positions (m, 2), half-edges (m, 2, 2) as columns) of seed_disk_polar with n rings."""
    dr = radius / (n + 0.5)
    xs, es = [], []
    if first_ring == 0:
        xs.append(centre)
        es.append(np.eye(2) * 0.25 * np.sqrt(np.pi) * dr)
    for i in range(max(first_ring, 1), n + 1):
        count = max(3, round(2 * np.pi * i))
        dth = 2 * np.pi / count
        for k in range(count):
            th = (0.5 * dth if i % 2 == 0 else 0.0) + k * dth
            er, et = np.array([np.cos(th), np.sin(th)]), np.array([-np.sin(th), np.cos(th)])
            xs.append(np.asarray(centre) + i * dr * er)
            es.append(np.column_stack([0.5 * dr * er, 0.5 * i * dr * dth * et]))
    return np.array(xs, float), np.array(es)


def snapshot(disks, pressure=1e6):
    """(positions (n, 3) [m], VTU arrays) of grains given as (positions, half-edges) [m]."""
    x = np.concatenate([d[0] for d in disks])
    e = np.concatenate([d[1] for d in disks])
    n = len(x)
    stress = np.zeros((n, 9))
    stress[:, 0] = stress[:, 4] = stress[:, 8] = -pressure
    pad = np.zeros((n, 1))
    arr = {"velocity": np.zeros((n, 3)), "stress": stress, "pressure": np.full(n, pressure),
           "J": np.ones(n), "mass": np.ones(n),
           "volume": 4 * np.abs(np.linalg.det(e)),
           "grain": np.concatenate([np.full(len(d[0]), g) for g, d in enumerate(disks)]),
           "domain_e1": np.hstack([e[:, :, 0], pad]), "domain_e2": np.hstack([e[:, :, 1], pad])}
    return np.hstack([x, pad]), arr


def render(pts, arr, field, **kw):
    """(RGB image (h, w, 3) in [0, 1], pixel coordinates of a data point [mm], axes, values)."""
    corners, _ = ps.domains(pts[:, :2] * 1e3, arr, None)
    fig, ax, values = ps.draw_snapshot(pts, arr, field, corners, **kw)
    fig.set_dpi(100)
    fig.canvas.draw()
    img = np.asarray(fig.canvas.buffer_rgba())[:, :, :3] / 255.0
    height = img.shape[0]

    def pixel(xy):
        px, py = ax.transData.transform(xy)
        return px, height - py  # image rows count from the top

    ps.plt.close(fig)
    return img, pixel, ax, values


def pixels_within(img, pixel, centre_mm, r_mm, r_in_mm=0.0):
    """The image's pixels whose centres lie in the ring r_in <= r < r of a circle [mm]."""
    cx, cy = pixel(centre_mm)
    rx = abs(pixel((centre_mm[0] + r_mm, centre_mm[1]))[0] - cx)
    rin = abs(pixel((centre_mm[0] + r_in_mm, centre_mm[1]))[0] - cx)
    yy, xx = np.mgrid[0:img.shape[0], 0:img.shape[1]]
    d = np.hypot(xx + 0.5 - cx, yy + 0.5 - cy)
    return img[(d < rx) & (d >= rin)], rx


class NoGaps(unittest.TestCase):
    R = 1e-3  # m

    def check_filled(self, field):
        pts, arr = snapshot([polar_disk((0.0, 0.0), self.R, 8)])
        img, pixel, _, _ = render(pts, arr, field)
        # Inside the disk, 3 px off its edge (the outline's anti-aliasing).
        r_px = abs(pixel((1.0, 0.0))[0] - pixel((0.0, 0.0))[0])
        inside, _ = pixels_within(img, pixel, (0.0, 0.0), 1.0 - 3.0 / r_px)
        face = np.median(inside, axis=0)
        background = np.all(inside > 0.97, axis=1).sum()
        off = np.abs(inside - face).max(axis=1)
        print(f"{field}: {len(inside)} pixels inside the grain (radius {r_px:.0f} px), face "
              f"{np.round(face, 3).tolist()}, background pixels {background}, largest channel "
              f"deviation {off.max():.4f}")
        self.assertGreater(len(inside), 10000)
        self.assertFalse(np.all(face > 0.97), "the grain is not filled")
        self.assertEqual(background, 0)
        self.assertLess(off.max(), 3.5 / 255, "seams (lighter pixels) inside the grain")

    def test_grain_palette(self):
        self.check_filled("grain")

    def test_grain_pressure(self):
        self.check_filled("pressure")

    def test_point_pressure(self):
        self.check_filled("point_pressure")

    def test_annulus_keeps_its_hole(self):
        # Rings 4..8 of a polar disk: a hole of radius 3.5 dr, wider than any domain.
        pts, arr = snapshot([polar_disk((0.0, 0.0), self.R, 8, first_ring=4)])
        img, pixel, _, _ = render(pts, arr, "pressure")
        dr = 1.0 / 8.5
        hole, _ = pixels_within(img, pixel, (0.0, 0.0), 3.0 * dr)
        ring, _ = pixels_within(img, pixel, (0.0, 0.0), 7.5 * dr, 4.5 * dr)
        print(f"annulus: hole {len(hole)} pixels, {np.all(hole > 0.97, axis=1).mean():.4f} "
              f"background; ring {len(ring)} pixels, {np.all(ring > 0.97, axis=1).sum()} "
              "background")
        self.assertTrue(np.all(hole > 0.97))
        self.assertEqual(np.all(ring > 0.97, axis=1).sum(), 0)


class DistinctNeighbours(unittest.TestCase):
    def test_hexagon_of_touching_disks(self):
        r = 0.5e-3
        centres = [(0.0, 0.0)] + [(2 * r * np.cos(a), 2 * r * np.sin(a))
                                  for a in np.arange(6) * np.pi / 3] + [(6 * r, 6 * r)]
        pts, arr = snapshot([polar_disk(c, r, 4) for c in centres])
        _, _, _, colour = render(pts, arr, "grain", gap=0.05, colours=8)
        touching = [(a, b) for a in range(8) for b in range(a + 1, 8)
                    if np.hypot(*np.subtract(centres[a], centres[b])) < 2.01 * r]
        print(f"hexagon: {len(touching)} touching pairs, colours "
              f"{[colour[g] for g in range(8)]}")
        self.assertEqual(len(touching), 12)
        for a, b in touching:
            self.assertNotEqual(colour[a], colour[b], f"grains {a} and {b} touch")

    def test_contact_list_counts(self):
        # Two grains far apart but listed as in contact (the forces CSV) differ; with the
        # palette of one colour, a third unrelated grain reuses it.
        r = 0.5e-3
        pts, arr = snapshot([polar_disk(c, r, 3) for c in ((0, 0), (3 * r, 0), (0, 3 * r))])
        _, _, _, colour = render(pts, arr, "grain", gap=0.05, contacts=[(0, 1)], colours=1)
        print(f"contact list: colours {[colour[g] for g in range(3)]}")
        self.assertNotEqual(colour[0], colour[1])
        self.assertEqual(colour[2], colour[0])

    def test_wheel_graph(self):
        # A centre joined to a 6-cycle: 3 colours are needed, also with a palette of 2.
        pairs = [(0, k) for k in range(1, 7)] + [(k, k % 6 + 1) for k in range(1, 7)]
        for size in (2, 8):
            colour = ps.colour_graph(range(7), pairs, size)
            print(f"wheel, palette {size}: {[colour[g] for g in range(7)]}")
            for a, b in pairs:
                self.assertNotEqual(colour[a], colour[b])
        self.assertEqual(len(set(ps.colour_graph(range(7), pairs, 2).values())), 3)


def run_folder(path, vtu_arrays=None, csv_header="step,time,phi,eps"):
    """A synthetic output folder of `mpmcd run`: a box, two snapshots of four disks."""
    os.makedirs(path, exist_ok=True)
    r, L = 0.5e-3, 2e-3
    with open(os.path.join(path, "input.toml"), "w") as f:
        f.write('[simulation]\nname = "syn"\n[grid]\ncell_size = 5e-5\n'
                '[[materials]]\nname = "gel"\nlambda = 3e6\nmu = 1.5e6\n')
        for name, p, n in (("bottom", (0, 0), (0, 1)), ("top", (0, L), (0, -1)),
                           ("left", (0, 0), (1, 0)), ("right", (L, 0), (-1, 0))):
            f.write(f'[[walls]]\nname = "{name}"\npoint = [{p[0]}, {p[1]}]\n'
                    f'normal = [{n[0]}, {n[1]}]\n')
    with open(os.path.join(path, "syn.csv"), "w") as f:
        f.write(csv_header + "\n0,0,0.78,0\n1,1e-5,0.785,-0.01\n")
    centres = [(r, r), (3 * r, r), (r, 3 * r), (3 * r, 3 * r)]
    pts, arr = snapshot([polar_disk(c, r, 4) for c in centres])
    with open(os.path.join(path, "syn.pvd"), "w") as f:
        f.write('<VTKFile type="Collection">\n<Collection>\n')
        for n, t in enumerate((0.0, 1e-5)):
            f.write(f'<DataSet timestep="{t}" group="" part="0" file="syn_{n:06d}.vtu"/>\n')
            write_vtu(os.path.join(path, f"syn_{n:06d}.vtu"), pts,
                      arr if vtu_arrays is None else vtu_arrays(arr))
            with open(os.path.join(path, f"syn_grains_{n:06d}.csv"), "w") as g:
                g.write("time,grain,x,y\n" + "".join(f"{t},{k},{c[0]},{c[1]}\n"
                                                      for k, c in enumerate(centres)))
            with open(os.path.join(path, f"syn_forces_{n:06d}.csv"), "w") as g:
                g.write(f"time,a,b,fn,px,py\n{t},0,1,10,{2 * r},{r}\n{t},0,2,5,{r},{2 * r}\n"
                        f"{t},-1,0,7,{r},0\n")
        f.write("</Collection>\n</VTKFile>\n")


def plot(*args):
    cmd = [sys.executable, os.path.join(TOOLS, "plot_snapshots.py"), *args]
    return subprocess.run(cmd, capture_output=True, text=True)


class CommandLine(unittest.TestCase):
    def test_formats_and_forces(self):
        folder = os.path.join(WORK, "run_ok")
        run_folder(folder)
        out = os.path.join(folder, "pics")
        for field in ("grain", "pressure", "point_pressure"):
            res = plot(folder, "--phi", "0.785", "--field", field, "--forces", "-o", out,
                       "--format", "png", "pdf", "svg")
            print(res.stdout.strip())
            self.assertEqual(res.returncode, 0, res.stderr)
            self.assertIn("domains of the VTU", res.stdout)
            stem = os.path.join(out, f"snapshot_phi0.785_{field}_forces")
            with open(stem + ".pdf", "rb") as f:
                self.assertEqual(f.read(5), b"%PDF-")
            with open(stem + ".svg") as f:
                svg = f.read()
            self.assertIn("<svg", svg)
            self.assertNotIn("Figure", svg)
            self.assertLess(len(svg), 2_000_000)  # shading inside grains is an embedded image
            self.assertTrue(os.path.getsize(stem + ".png") > 1000)

    def check_refused(self, folder, *expected, args=()):
        res = plot(folder, "--phi", "0.78", *args)
        print(f"refused: {res.stderr.strip()}")
        self.assertEqual(res.returncode, 2, res.stdout + res.stderr)
        for text in expected:
            self.assertIn(text, res.stderr)

    def test_bad_input(self):
        self.check_refused(os.path.join(WORK, "nothing"), "input.toml",
                           "expected the output folder")
        folder = os.path.join(WORK, "run_nophi")
        run_folder(folder, csv_header="step,time,volume,eps")
        self.check_refused(folder, "syn.csv", "missing phi")
        folder = os.path.join(WORK, "run_nograin")
        run_folder(folder, vtu_arrays=lambda a: {k: v for k, v in a.items() if k != "grain"})
        self.check_refused(folder, "syn_000000.vtu", "'grain'")
        folder = os.path.join(WORK, "run_noforces")
        run_folder(folder)
        for n in range(2):
            os.remove(os.path.join(folder, f"syn_forces_{n:06d}.csv"))
        self.check_refused(folder, "--forces", "syn_000000.vtu", "grains = true",
                           args=("--forces",))


if __name__ == "__main__":
    unittest.main(verbosity=2)
