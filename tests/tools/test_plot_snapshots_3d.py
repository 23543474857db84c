#!/usr/bin/python3
"""Tests of tools/plot_snapshots_3d.py (ctest unit/tools/PlotSnapshots3D).

Usage: test_plot_snapshots_3d.py [workdir [mpmcd-binary]]   (or the binary in $MPMCD_BINARY)

- the section of a domain (a parallelepiped) by a plane: a cube turned about the plane's normal
  gives the turned square, turned about an in-plane axis a rectangle 1/cos(angle) wide;
- on a real 3D run (`mpmcd run`, five spheres in a box of six walls, the top wall squeezing
  them, about 1 s): the points in each slab are those a numpy count gives, at t = 0 one lattice
  layer;
  a grain's outline covers its domains' sections (which tile at t = 0) and is centred on the
  sphere; the outer points are the sphere's outer shell, their normals radial; grains that touch
  (points of two grains within 1.2 spacings) never share a colour, also with a palette of 2;
  the walls' positions at the snapshot follow the CSV's h; the command writes PNG, PDF and SVG
  slices and views for --phi, --time and --index and each field;
- bad input: exit 2 with a message naming the file (a 2D run given to the 3D command, a 3D run to
  the 2D one, --phi without a box, --index past the series, a VTU without `grain`).
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
TOOLS = os.path.join(HERE, "..", "..", "tools")
sys.path.insert(0, TOOLS)
sys.path.insert(0, HERE)
import plot_snapshots_3d as p3  # noqa: E402
from vtu_points import read_vtu, write_vtu  # noqa: E402

WORK = sys.argv.pop(1) if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="plot_snapshots_3d_")
MPMCD = sys.argv.pop(1) if len(sys.argv) > 1 else os.environ.get("MPMCD_BINARY")

R = 0.6e-3  # sphere radius [m]
# Four spheres touching in a square (y = 1.4 mm), a fifth on them, a hair apart; the top wall,
# 0.01 mm above the fifth, squeezes it by 0.14 mm in 3e-4 s (25 steps, under a second).
CENTRES = [(1.4e-3, 1.4e-3, 1.4e-3), (2.6e-3, 1.4e-3, 1.4e-3), (1.4e-3, 1.4e-3, 2.6e-3),
           (2.6e-3, 1.4e-3, 2.6e-3), (2.0e-3, 2.25e-3, 2.0e-3)]
WALLS = (("left", (8e-4, 0, 0), (1.0, 0, 0)), ("right", (3.2e-3, 0, 0), (-1.0, 0, 0)),
         ("bottom", (0, 8e-4, 0), (0, 1.0, 0)), ("top", (0, 2.86e-3, 0), (0, -1.0, 0)),
         ("front", (0, 0, 8e-4), (0, 0, 1.0)), ("back", (0, 0, 3.2e-3), (0, 0, -1.0)))
INPUT = """[simulation]
name = "mini"
dimension = 3
threads = 1
[grid]
origin = [0.0, 0.0, 0.0]
extent = [0.004, 0.004, 0.004]
cell_size = 0.0004
[[materials]]
name = "gel"
law = "neo_hookean"
density = 990.0
lambda = 3e6
mu = 1.5e6
""" + "".join(f"""[[grains]]
shape = "sphere"
material = "gel"
center = [{c[0]}, {c[1]}, {c[2]}]
radius = {R}
""" for c in CENTRES) + "".join(f"""[[walls]]
name = "{name}"
point = [{p[0]}, {p[1]}, {p[2]}]
normal = [{n[0]}, {n[1]}, {n[2]}]
""" for name, p, n in WALLS) + """
[loading]
[[loading.stages]]
name = "squeeze"
until = { phi = 0.9 }
[[loading.stages.walls]]
name = "top"
velocity = [0.0, -0.5, 0.0]
[time]
dt = 2e-5
end_time = 3e-4
[output]
folder = "out"
vtu_interval = 1.5e-4
"""

_RUN = None


def real_run():
    """The output folder of the five-sphere run (made once)."""
    global _RUN
    if _RUN is None:
        if not MPMCD or not os.access(MPMCD, os.X_OK):
            raise unittest.SkipTest("no mpmcd binary (argument 2 or $MPMCD_BINARY)")
        folder = os.path.join(WORK, "run3d")
        shutil.rmtree(folder, ignore_errors=True)
        os.makedirs(folder)
        with open(os.path.join(folder, "mini.toml"), "w") as f:
            f.write(INPUT)
        res = subprocess.run([MPMCD, "run", "mini.toml"], cwd=folder, capture_output=True,
                             text=True)
        if res.returncode != 0:
            raise RuntimeError(f"mpmcd run failed: {res.stdout[-2000:]}{res.stderr[-2000:]}")
        _RUN = os.path.join(folder, "out")
    return _RUN


def plot3d(*args):
    cmd = [sys.executable, os.path.join(TOOLS, "plot_snapshots_3d.py"), *args]
    return subprocess.run(cmd, capture_output=True, text=True)


def shoelace(poly):
    return 0.5 * np.sum(poly[:, 0] * np.roll(poly[:, 1], -1) - np.roll(poly[:, 0], -1) * poly[:, 1])


class Sections(unittest.TestCase):
    def test_cube_turned_about_the_normal(self):
        a, th = 1.0, 0.3
        rot = np.array([[1, 0, 0], [0, np.cos(th), -np.sin(th)], [0, np.sin(th), np.cos(th)]])
        x = np.array([[5.0, 1.0, 2.0]])
        poly, cut = p3.sections(x, (a * rot)[None], 0, 5.2)  # plane x = 5.2, (z, y) coordinates
        area = shoelace(poly[0])
        print(f"cube turned about x, cut by x = c: area {area:.12f} (4 a^2 = 4), cut {cut[0]}")
        self.assertTrue(cut[0])
        self.assertAlmostEqual(area, 4 * a * a, places=12)  # counter-clockwise: positive

    def test_cube_turned_about_an_in_plane_axis(self):
        a, th = 0.5, 0.4
        rot = np.array([[np.cos(th), 0, np.sin(th)], [0, 1, 0], [-np.sin(th), 0, np.cos(th)]])
        x = np.zeros((1, 3))
        poly, cut = p3.sections(x, (a * rot)[None], 0, 0.0)
        area = shoelace(poly[0])
        width = np.ptp(poly[0][:, 0])
        print(f"cube turned about y, cut through its centre: area {area:.12f} "
              f"(expected {4 * a * a / np.cos(th):.12f}), width {width:.12f}")
        self.assertAlmostEqual(area, 4 * a * a / np.cos(th), places=12)
        self.assertAlmostEqual(width, 2 * a / np.cos(th), places=12)
        # A plane that misses the domain: the section through the point, flagged.
        poly, cut = p3.sections(x, (a * rot)[None], 0, 5.0)
        self.assertFalse(cut[0])
        self.assertAlmostEqual(shoelace(poly[0]), 4 * a * a / np.cos(th), places=12)


class RealRun(unittest.TestCase):
    def snapshot(self, n):
        return read_vtu(os.path.join(real_run(), f"mini_{n:06d}.vtu"))

    def test_slab_counts_and_sections(self):
        folder = real_run()
        out = os.path.join(WORK, "pics")
        res = plot3d(folder, "--index", "0", "-1", "--what", "slices", "-o", out)
        print(res.stdout.strip())
        self.assertEqual(res.returncode, 0, res.stderr)
        printed = re.findall(r"([xyz]) = (\S+) m: (\d+) points in the slab", res.stdout)
        self.assertEqual(len(printed), 6)
        for k, n in enumerate((0, 2)):
            pts, arr = self.snapshot(n)
            s = np.median(np.cbrt(arr["volume"]))
            lo, hi = pts.min(axis=0), pts.max(axis=0)
            for a in range(3):
                c = lo[a] + 0.5 * (hi[a] - lo[a]) + 0.25 * s
                count = np.count_nonzero(np.abs(pts[:, a] - c) <= s / 2)
                name, c_printed, n_printed = printed[3 * k + a]
                print(f"snapshot {n}, {name} = {c:.6g} m: {n_printed} printed, numpy {count}")
                self.assertEqual(name, "xyz"[a])
                self.assertAlmostEqual(float(c_printed), c, delta=1e-5 * c)  # %.6g
                self.assertEqual(int(n_printed), count)
                self.assertGreater(count, 20)
                if n == 0:  # one lattice layer
                    layer = pts[np.abs(pts[:, a] - c) <= s / 2, a]
                    self.assertLess(np.ptp(layer), 1e-12)

    def test_section_areas(self):
        # The plane y = c cuts the four lower spheres; at t = 0 their domains in the slab are
        # lattice squares, which tile: a grain's outline covers them with no gap (area at least
        # their sum) and closes only the staircase's notches (at most a quarter more), and is
        # centred on the sphere.
        pts, arr = self.snapshot(0)
        s = np.median(np.cbrt(arr["volume"]))
        c = 1.4e-3 + 0.3 * R
        colours = {g: "#66c2a5" for g in range(5)}
        fig, drawn = p3.draw_slices(pts, arr, "grain", [(1, c)], s, colours)
        p3.plt.close(fig)
        _, _, n, shapes = drawn[0]
        inside = p3.slab(pts, 1, c, s)
        edges, _ = p3.half_edges(pts, arr)
        polys, cut = p3.sections(pts[inside], edges[inside], 1, c)
        self.assertTrue(cut.all())
        grain = arr["grain"][inside]
        for g in range(4):
            v = shapes[g].vertices[shapes[g].triangles]
            tri = 0.5 * np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
            area = tri.sum()
            centroid = np.sum(tri[:, None] * v.mean(axis=1), axis=0) / area
            domains = sum(shoelace(q) for q in polys[grain == g]) * 1e6
            print(f"grain {g}: {np.sum(grain == g)} points, outline area {area:.5f} mm^2, their "
                  f"sections' {domains:.5f} mm^2, centroid {np.round(centroid, 9).tolist()} mm "
                  f"(sphere's ({CENTRES[g][0] * 1e3:g}, {CENTRES[g][2] * 1e3:g}))")
            self.assertTrue(np.all(tri > 0))  # counter-clockwise
            self.assertGreaterEqual(area, domains * (1 - 1e-9))
            self.assertLess(area, 1.25 * domains)
            np.testing.assert_allclose(centroid, np.array(CENTRES[g])[[0, 2]] * 1e3, atol=1e-9)
        self.assertNotIn(4, shapes)  # the top sphere is not cut
        self.assertEqual(n, np.count_nonzero(inside))

    def test_touching_grains_differ(self):
        for n in (0, 2):
            pts, arr = self.snapshot(n)
            grain = arr["grain"].astype(int)
            s = np.median(np.cbrt(arr["volume"]))
            touching = set()
            for a in range(5):
                for b in range(a + 1, 5):
                    d = np.linalg.norm(pts[grain == a][:, None] - pts[grain == b][None], axis=2)
                    if d.min() < 1.2 * s:
                        touching.add((a, b))
            outer = p3.outer_points(pts, grain, np.cbrt(arr["volume"]))
            for size, cell in ((8, 4e-4), (2, 0.0)):
                colours, pairs = p3.colour_grains(pts, arr, grain, outer[0], cell, (), size)
                print(f"snapshot {n}: touching {sorted(touching)}; palette {size}, gap {cell} m: "
                      f"{[colours[g] for g in range(5)]}")
                self.assertGreaterEqual(len(touching), 8)  # the square and the top sphere
                for a, b in touching:
                    self.assertNotEqual(colours[a], colours[b], f"grains {a} and {b} touch")
            self.assertEqual(len(set(colours.values())), 3)  # the wheel needs 3

    def test_outer_points(self):
        pts, arr = self.snapshot(0)
        grain = arr["grain"].astype(int)
        outer, normal = p3.outer_points(pts, grain, np.cbrt(arr["volume"]))
        for g, c in enumerate(CENTRES):
            r = np.linalg.norm(pts[grain == g] - c, axis=1)
            o = outer[grain == g]
            radial = (pts[grain == g] - c) / r[:, None]
            print(f"grain {g}: {o.sum()} outer of {len(o)}, outer r >= {r[o].min() / R:.3f} R, "
                  f"inner r <= {r[~o].max() / R:.3f} R, normal . radial >= "
                  f"{np.min(np.sum(normal[grain == g][o] * radial[o], axis=1)):.3f}")
            self.assertGreater(r[o].min(), r[~o].max() - 0.5 * R)  # no deep point is outer
            self.assertGreater(o.sum(), 0.4 * len(o))
            self.assertGreater(np.min(np.sum(normal[grain == g][o] * radial[o], axis=1)), 0.3)
        # The last snapshot, squeezed: with the first as reference, the same points are outer.
        last, arr2 = self.snapshot(2)
        outer2, normal2 = p3.outer_points(last, grain, np.cbrt(arr2["volume"]), pts)
        print(f"last snapshot: {outer2.sum()} outer (first {outer.sum()}), normals . first's >= "
              f"{np.min(np.sum(normal2[outer] * normal[outer], axis=1)):.3f}")
        np.testing.assert_array_equal(outer2, outer)
        self.assertGreater(np.min(np.sum(normal2[outer] * normal[outer], axis=1)), 0.8)

    def test_walls_follow_the_csv(self):
        folder = real_run()
        cfg, cols, _ = p3.read_run(folder, ("time", "h"), [f"wall_top_v{a}" for a in "xyz"])
        for k, t in enumerate(cols["time"]):
            walls = {name: p for name, p, _ in p3.walls_at(cfg, cols, t)}
            self.assertAlmostEqual(walls["top"][1] - walls["bottom"][1], cols["h"][k], delta=1e-12)
        print(f"top wall at the end: y = {walls['top'][1]:.6g} m, h = {cols['h'][-1]:.6g} m")

    def test_formats_fields_and_selections(self):
        # --index is in test_slab_counts_and_sections; here --phi and --time on the command line,
        # the other fields in-process (each command costs a Python start with matplotlib).
        folder = real_run()
        out = os.path.join(WORK, "pics_all")
        for field, sel, formats in (("grain", ["--phi", "0.37"], ["png", "pdf", "svg"]),
                                    ("point_pressure", ["--time", "1e-4"], ["png"])):
            res = plot3d(folder, *sel, "--field", field, "-o", out, "--format", *formats,
                         "--axis", "x", "y", "--at", "0.4", "0.6")
            print(res.stdout.strip())
            self.assertEqual(res.returncode, 0, res.stderr)
            label = {"--phi": "phi0.370", "--time": "t0.0001"}[sel[0]]
            for what in ("slices", "view"):
                stem = os.path.join(out, f"{what}_{label}_{field}")
                self.assertGreater(os.path.getsize(stem + ".png"), 5000)
                if "pdf" in formats:
                    with open(stem + ".pdf", "rb") as f:
                        self.assertEqual(f.read(5), b"%PDF-")
                    with open(stem + ".svg") as f:
                        self.assertIn("<svg", f.read())
        pts, arr = self.snapshot(2)
        for field in ("pressure", "J"):
            lo, hi = p3.scale(arr, field, (None, None))
            planes = [(0, 2.05e-3), (2, 2.05e-3)]
            fig, drawn = p3.draw_slices(pts, arr, field, planes, 1.9e-4, None,
                                        value_range=(lo, hi))
            self.assertEqual(len(fig.axes), 3)  # two panels and the colour bar
            counts = [np.count_nonzero(np.abs(pts[:, a] - c) <= 0.95e-4) for a, c in planes]
            self.assertEqual([n for _, _, n, _ in drawn], counts)
            p3.plt.close(fig)
            fig, n = p3.draw_view(pts, arr, field, None, value_range=(lo, hi))
            print(f"{field}: scale [{lo:.4g}, {hi:.4g}], view of {n} points")
            self.assertLess(lo, hi)
            self.assertEqual(len(fig.axes), 2)  # the view and the colour bar
            self.assertGreater(n, 0)
            p3.plt.close(fig)


def plot2d(*args):
    cmd = [sys.executable, os.path.join(TOOLS, "plot_snapshots.py"), *args]
    return subprocess.run(cmd, capture_output=True, text=True)


class BadInput(unittest.TestCase):
    def refused(self, res, *expected):
        print(f"refused: {res.stderr.strip()}")
        self.assertEqual(res.returncode, 2, res.stdout + res.stderr)
        for text in expected:
            self.assertIn(text, res.stderr)

    def test_dimension_mismatch(self):
        import test_plot_snapshots as t2
        folder = os.path.join(WORK, "run2d")
        t2.run_folder(folder)
        self.refused(plot3d(folder, "--phi", "0.78"), "input.toml", "expected a 3D run")
        self.refused(plot2d(real_run(), "--phi", "0.4"), "input.toml", "expected a 2D run")

    def test_bad_selection_and_files(self):
        src = real_run()
        self.refused(plot3d(src, "--index", "7"), "--index 7", "3 snapshots")
        folder = os.path.join(WORK, "run3d_nophi")
        shutil.rmtree(folder, ignore_errors=True)
        shutil.copytree(src, folder)
        with open(os.path.join(folder, "mini.csv")) as f:
            text = f.read()
        with open(os.path.join(folder, "mini.csv"), "w") as f:
            f.write(text.replace(",phi,", ",volume_fraction,", 1))
        self.refused(plot3d(folder, "--phi", "0.4"), "mini.csv", "missing phi")
        res = plot3d(folder, "--index", "0", "--what", "slices", "-o", os.path.join(folder, "p"))
        self.assertEqual(res.returncode, 0, res.stderr)  # by index, no Φ is needed
        pts, arr = read_vtu(os.path.join(folder, "mini_000001.vtu"))
        write_vtu(os.path.join(folder, "mini_000001.vtu"), pts,
                  {k: v for k, v in arr.items() if k not in ("grain", "connectivity", "offsets",
                                                             "types")})
        self.refused(plot3d(folder, "--index", "1"), "mini_000001.vtu", "'grain'")


if __name__ == "__main__":
    unittest.main(verbosity=2)
