#!/usr/bin/python3
"""Pictures of the grains of a run at chosen solid fractions Φ (the paper's Figure 3, for print).

Usage: plot_snapshots.py <run-folder> --phi 0.78 0.9 0.97
                         [--field grain|pressure|point_pressure|J] [--colours 8] [--range lo hi]
                         [-o out-folder] [--dots] [--squares] [--dpi 150] [--forces]
                         [--format png pdf svg] [--no-title]

For each Φ asked, takes the VTU snapshot of the run (series <name>.pvd) whose time is nearest to
the CSV row (<name>.csv, column phi) with the nearest Φ, and draws every grain as one filled
outline: the union of its material points' domains (the parallelograms x + e1 s1 + e2 s2,
s in [-1, 1]², of the VTU arrays domain_e1, domain_e2; for snapshots without them, the initial
square of side sqrt(V0) mapped by a deformation gradient estimated from the neighbours' motion
since the first snapshot; --squares: squares of side sqrt(V)), closed over the slivers between
domains, with a thin dark boundary (docs/observables.md, "Pictures").

--field grain: a categorical palette of --colours colours (default 8) in which neighbouring grains
never share a colour (greedy DSatur colouring of the graph of grains in contact, from the forces
CSV when there is one, or whose outlines come within one grid cell); pressure: each grain in
one colour, its pressure P = -(σxx + σyy)/2 of its volume-averaged stress [MPa] (the `pressure`
of the grains CSV); point_pressure and J: the points' -tr σ/3 [MPa] or J, varying inside the
grains. --range lo hi fixes the colour scale (the same for every Φ). The walls of input.toml are
drawn as lines at that time; --dots adds the material points as black dots (as in the paper).
--forces draws the contact-force network over the grains (runs with [output] grains = true: the
snapshot's <name>_forces_<n>.csv and <name>_grains_<n>.csv): a line between the centroids of each
pair of grains in contact (from the contact point to the centroid for a wall), its width
proportional to the normal force (the mean force draws 1.5 pt).
Writes <out>/snapshot_phi<Φ>_<field>[_forces].<format> for each --format (default png; pdf and
svg are vector) in <out> (default <run-folder>/snapshots) and prints what it took. Bad input:
a message naming the file and what was expected, exit code 2.
Needs numpy, scipy and matplotlib (/usr/bin/python3 on Debian 12); no ParaView.
"""
import argparse
import csv
import os
import re
import sys
import tomllib
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection, PatchCollection  # noqa: E402
from matplotlib.patches import PathPatch  # noqa: E402
from matplotlib.path import Path  # noqa: E402
from scipy.spatial import Delaunay, QhullError, cKDTree  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from vtu_points import read_vtu  # noqa: E402

FIELDS = ["grain", "pressure", "point_pressure", "J"]
# ColorBrewer Set2 (8 colours, print- and colour-blind-friendly); tab20 when more are needed.
PALETTE = ["#66c2a5", "#fc8d62", "#8da0cb", "#e78ac3", "#a6d854", "#ffd92f", "#e5c494", "#b3b3b3"]
OUTLINE = "#262626"


class InputError(Exception):
    """Bad input: the message names the file and what was expected (exit code 2)."""


def fail(msg):
    print(f"plot_snapshots.py: {msg}", file=sys.stderr)
    sys.exit(2)


def read_run(folder, required=("time", "phi", "eps"), optional=()):
    """(input dict, CSV columns dict, [(time, vtu path)]) of an mpmcd output folder: the CSV's
    `required` columns (refused when missing) and those of `optional` it has, as arrays."""
    path = os.path.join(folder, "input.toml")
    if not os.path.isfile(path):
        raise InputError(f"{path}: no input copy (expected the output folder of `mpmcd run`)")
    try:
        with open(path, "rb") as f:
            cfg = tomllib.load(f)
    except tomllib.TOMLDecodeError as e:
        raise InputError(f"{path}: expected the TOML input copy of `mpmcd run`: {e}")
    name = cfg.get("simulation", {}).get("name", "mpmcd")
    csv_path = os.path.join(folder, name + ".csv")
    if not os.path.isfile(csv_path):
        raise InputError(f"{csv_path}: no CSV time series")
    with open(csv_path, newline="") as f:
        rows = list(csv.DictReader(f))
    missing = [k for k in required if not rows or k not in rows[0]]
    box = " (the walls must form a box)" if "phi" in missing else ""
    if missing:
        raise InputError(f"{csv_path}: expected the columns {', '.join(required)}{box}; missing "
                         f"{', '.join(missing)}")
    keys = list(required) + [k for k in optional if k in rows[0] and k not in required]
    try:
        cols = {k: np.array([float(r[k]) for r in rows]) for k in keys}
    except (TypeError, ValueError):
        raise InputError(f"{csv_path}: expected numbers in the columns {', '.join(keys)}")
    pvd = os.path.join(folder, name + ".pvd")
    if not os.path.isfile(pvd):
        raise InputError(f"{pvd}: no VTU series (set [output] vtu = true)")
    with open(pvd) as f:
        series = [(float(t), os.path.join(folder, file)) for t, file in
                  re.findall(r'timestep="([^"]+)"[^>]*file="([^"]+)"', f.read())]
    if not series:
        raise InputError(f"{pvd}: expected <DataSet timestep=... file=...> entries, found none")
    return cfg, cols, series


def read_snapshot(path):
    """(positions (n, 3) [m], arrays) of a VTU snapshot, checked for what the pictures need."""
    if not os.path.isfile(path):
        raise InputError(f"{path}: no such snapshot (listed in the .pvd series)")
    try:
        pts, arr = read_vtu(path)
    except (ValueError, KeyError, IndexError) as e:
        raise InputError(f"{path}: expected an mpmcd point-cloud VTU (raw appended data): {e}")
    if pts is None or pts.ndim != 2 or pts.shape[1] != 3:
        raise InputError(f"{path}: expected point positions with 3 components")
    n = len(pts)
    for key, comps in (("grain", 1), ("volume", 1), ("stress", 9)):
        a = arr.get(key)
        if a is None or len(a) != n or (comps > 1 and (a.ndim != 2 or a.shape[1] != comps)):
            raise InputError(f"{path}: expected the point-data array '{key}' ({comps} "
                             f"component{'s' if comps > 1 else ''} per point, {n} points)")
    return pts, arr


def wall_segments(cfg, t):
    """Each wall as (point at time t, direction along the wall)."""
    out = []
    for w in cfg.get("walls", []):
        p = np.array(w["point"], float) + t * np.array(w.get("velocity", [0.0, 0.0]), float)
        n = np.array(w["normal"], float)
        n /= np.linalg.norm(n)
        out.append((p, np.array([-n[1], n[0]])))
    return out


CORNERS = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float)


def domains(xy, arr, first):
    """Corners (n, 4, 2) of each point's domain, counter-clockwise for a positive det F, in the
    units of `xy`. From the VTU arrays domain_e1, domain_e2 (the domain x + e1 s1 + e2 s2); else
    the initial square (side sqrt(V0)) mapped by the point's deformation gradient, estimated by
    least squares from the motion of its neighbours in the same grain since the first snapshot
    `first` = (positions, arrays); a plain square of side sqrt(V) where neither is possible.
    Returns (corners, how)."""
    scale = 1e3  # m -> mm, as xy
    if "domain_e1" in arr and "domain_e2" in arr:
        e = np.stack([arr["domain_e1"][:, :2], arr["domain_e2"][:, :2]], axis=2) * scale
        return xy[:, None, :] + np.einsum("ikl,jl->ijk", e, CORNERS), "domains of the VTU"
    half = 0.5 * np.sqrt(arr["volume"]) * scale
    out = xy[:, None, :] + half[:, None, None] * CORNERS[None, :, :]
    if first is None or len(first[0]) != len(xy):
        return out, "squares of side sqrt(V)"
    X = first[0][:, :2] * scale
    half0 = 0.5 * np.sqrt(first[1]["volume"]) * scale
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
        quad = (xy[idx][:, None, :]
                + np.einsum("ikl,jl->ijk", F, CORNERS) * half0[idx][:, None, None])
        out[idx[ok]] = quad[ok]
    return out, "domains estimated from the motion since the first snapshot"


class GrainShape:
    """The region of one grain: the union of its points' domains with the slivers between them
    closed. `corners` (n, k, 2): each domain a convex polygon of k vertices in order (the 2D
    parallelograms, k = 4; the 3D sections of tools/plot_snapshots_3d.py, padded to k = 6 by
    repeating a vertex). `vertices` (m, 2), `owner` (m,) the point (row of the grain's corners)
    each vertex belongs to, `triangles` (k, 3) counter-clockwise, covering the region, `loops` its
    boundary (outer loops counter-clockwise, holes clockwise), each (l, 2).

    The vertices are the domains' corners and centres; a triangle of their Delaunay triangulation
    is kept when its longest edge is at most the longest diagonal (the largest distance between two
    corners) of the domains of its vertices
    (an alpha shape with the local point spacing as alpha): triangles inside a domain or bridging
    the sliver between neighbouring domains are kept, those spanning a concavity wider than a
    domain are not."""

    def __init__(self, corners):
        n, k = corners.shape[:2]
        pts = np.concatenate([corners.reshape(-1, 2), corners.mean(axis=1)])
        owner = np.concatenate([np.repeat(np.arange(n), k), np.arange(n)])
        # (A parallelogram's longest vertex distance is a diagonal: the same as before for k = 4.)
        diag = np.linalg.norm(corners[:, :, None, :] - corners[:, None, :, :],
                              axis=3).max(axis=(1, 2))
        # Corners shared by neighbouring domains become one vertex (its largest diagonal).
        tol = 1e-9 * max(np.ptp(pts, axis=0).max(), 1e-300)
        _, first, inverse = np.unique(np.round(pts / tol), axis=0, return_index=True,
                                      return_inverse=True)
        inverse = inverse.ravel()
        self.vertices, self.owner = pts[first], owner[first]
        reach = np.zeros(len(first))
        np.maximum.at(reach, inverse, diag[owner])
        try:
            tri = Delaunay(self.vertices).simplices
            v = self.vertices[tri]
            longest = np.max(np.linalg.norm(v - np.roll(v, 1, axis=1), axis=2), axis=1)
            tri = tri[longest <= (1 + 1e-9) * reach[tri].max(axis=1)]
        except (QhullError, ValueError):  # degenerate (collinear, too few points): the domains
            polys = inverse[:k * n].reshape(n, k)
            tri = np.concatenate([polys[:, [0, j, j + 1]] for j in range(1, k - 1)])
        v = self.vertices[tri]
        cross = ((v[:, 1, 0] - v[:, 0, 0]) * (v[:, 2, 1] - v[:, 0, 1])
                 - (v[:, 1, 1] - v[:, 0, 1]) * (v[:, 2, 0] - v[:, 0, 0]))
        tri = tri[np.abs(cross) > 0]
        flip = cross[np.abs(cross) > 0] < 0
        tri[flip] = tri[flip][:, [0, 2, 1]]
        self.triangles = tri
        self.loops = [self.vertices[loop] for loop in boundary_loops(tri)]

    def path(self):
        """The region as one matplotlib Path (outer loops and holes)."""
        verts, codes = [], []
        for loop in self.loops:
            verts += list(loop) + [loop[0]]
            codes += [Path.MOVETO] + [Path.LINETO] * (len(loop) - 1) + [Path.CLOSEPOLY]
        return Path(np.array(verts).reshape(-1, 2), codes)


def boundary_loops(tri):
    """Closed vertex loops of the boundary of the union of counter-clockwise triangles: the
    directed edges whose reverse is not an edge, chained (each vertex has as many boundary edges
    leaving as arriving, so every walk closes)."""
    edges = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    present = set(map(tuple, edges.tolist()))
    after = defaultdict(list)
    for a, b in edges.tolist():
        if (b, a) not in present:
            after[a].append(b)
    loops = []
    while after:
        start = next(iter(after))
        loop, v = [start], start
        while True:
            w = after[v].pop()
            if not after[v]:
                del after[v]
            if w == start:
                break
            loop.append(w)
            v = w
        loops.append(loop)
    return loops


def grain_shapes(corners, grain):
    """{grain id: GrainShape} of every grain present."""
    return {int(g): GrainShape(corners[grain == g]) for g in np.unique(grain)}


def neighbour_pairs(shapes, gap, contacts=()):
    """Pairs (a, b), a < b, of grains whose boundaries come within `gap` of each other (any two
    boundary vertices; boundary edges are at most a domain diagonal long), plus `contacts`."""
    pairs = {(min(a, b), max(a, b)) for a, b in contacts if a >= 0 and b >= 0 and a != b}
    ids = [g for g, s in shapes.items() for loop in s.loops for _ in loop]
    if ids:
        tree = cKDTree(np.concatenate([loop for s in shapes.values() for loop in s.loops]))
        for i, j in tree.query_pairs(gap):
            if ids[i] != ids[j]:
                pairs.add((min(ids[i], ids[j]), max(ids[i], ids[j])))
    return pairs


def colour_graph(nodes, pairs, size=8):
    """{node: colour index} with no pair sharing a colour: DSatur order (Brélaz 1979: the
    uncoloured node with the most distinct neighbour colours first; ties: most neighbours, then
    the smallest id); each node takes, among the first `size` colours its neighbours do not use,
    the one used least so far (so the palette is used evenly), and a colour beyond `size` only
    when its neighbours use all of them."""
    adj = {v: set() for v in nodes}
    for a, b in pairs:
        adj[a].add(b)
        adj[b].add(a)
    colour, count = {}, defaultdict(int)
    while len(colour) < len(adj):
        v = max((u for u in adj if u not in colour),
                key=lambda u: (len({colour[w] for w in adj[u] if w in colour}), len(adj[u]), -u))
        used = {colour[w] for w in adj[v] if w in colour}
        free = [c for c in range(size) if c not in used]
        c = (min(free, key=lambda c: (count[c], c)) if free
             else next(c for c in range(size, size + len(adj) + 1) if c not in used))
        colour[v] = c
        count[c] += 1
    return colour


def palette_colours(n):
    """n distinct colours: PALETTE, then tab20's when more are needed; None beyond those."""
    extra = [matplotlib.colors.to_hex(c) for c in plt.get_cmap("tab20").colors]
    colours = PALETTE + [c for c in extra if c not in PALETTE]
    return colours[:n] if n <= len(colours) else None


def vertex_values(shape, xy, values):
    """A grain's per-point `values` at the vertices of its GrainShape, from its points at `xy`
    (same units as the shape): inverse-distance weights of the 4 nearest points."""
    k = min(4, len(xy))
    d, j = cKDTree(xy).query(shape.vertices, k=k)
    d, j = d.reshape(len(d), k), j.reshape(len(j), k)
    w = 1.0 / np.maximum(d, 1e-9 * d.max()) ** 2
    return np.sum(w * values[j], axis=1) / w.sum(axis=1)


def grain_pressure(arr, grain, ids):
    """{grain: P [MPa]}, P = -(σxx + σyy)/2 of the volume average of the points' stresses."""
    s, vol = arr["stress"], arr["volume"]
    p = -(s[:, 0] + s[:, 4]) / 2
    return {g: float(np.sum(p[grain == g] * vol[grain == g]) / np.sum(vol[grain == g]) / 1e6)
            for g in ids}


def read_forces(folder, name, vtu):
    """(contact pairs [(a, b)], segments [mm], normal forces [N/m]) of the snapshot `vtu`, from
    its grains and forces CSVs; None when the run wrote none (no [output] grains = true)."""
    m = re.search(r"_(\d+)\.vtu$", vtu)
    if not m:
        return None
    gpath = os.path.join(folder, f"{name}_grains_{m.group(1)}.csv")
    fpath = os.path.join(folder, f"{name}_forces_{m.group(1)}.csv")
    if not (os.path.isfile(gpath) and os.path.isfile(fpath)):
        return None
    path = gpath
    try:
        with open(gpath, newline="") as f:
            centre = {int(r["grain"]): (float(r["x"]) * 1e3, float(r["y"]) * 1e3)
                      for r in csv.DictReader(f)}
        path = fpath
        pairs, segs, fn = [], [], []
        with open(fpath, newline="") as f:
            for r in csv.DictReader(f):
                a, b, force = int(r["a"]), int(r["b"]), float(r["fn"])
                pairs.append((a, b))
                if force <= 0 or b not in centre:
                    continue
                start = centre[a] if a >= 0 else (float(r["px"]) * 1e3, float(r["py"]) * 1e3)
                segs.append((start, centre[b]))
                fn.append(force)
    except (KeyError, TypeError, ValueError) as e:
        raise InputError(f"{path}: expected the columns of docs/observables.md (grains: grain, x, "
                         f"y; forces: a, b, fn, px, py) with numbers: {e!r}")
    return pairs, segs, np.array(fn)


def draw_snapshot(pts, arr, field, corners, walls=(), gap=None, contacts=(), network=None,
                  dots=False, title=None, colours=8, value_range=(None, None)):
    """The figure of one snapshot: positions [m], VTU arrays, domain corners [mm], walls as
    (point [m], direction), `gap` [mm] the distance within which grains are neighbours for
    --field grain (default: the largest domain diagonal), `contacts` more neighbour pairs,
    `network` (segments [mm], normal forces) the force lines, `value_range` the colour scale's
    ends (None: the data's). Returns (figure, axes,
    {grain: face colour} for --field grain, {grain: P [MPa]} for pressure, else None)."""
    xy = pts[:, :2] * 1e3  # mm
    grain = arr["grain"].astype(int)
    shapes = grain_shapes(corners, grain)
    lo, hi = corners.reshape(-1, 2).min(axis=0), corners.reshape(-1, 2).max(axis=0)
    for p, _ in walls:
        lo, hi = np.minimum(lo, p * 1e3), np.maximum(hi, p * 1e3)
    lo, hi = lo - 0.03 * (hi - lo).max(), hi + 0.03 * (hi - lo).max()
    # The figure takes the shape of the packing (saved with a tight bounding box).
    width = 6.4 if field != "grain" else 5.4
    fig, ax = plt.subplots(figsize=(width, 0.9 + (width - 1.6) * (hi[1] - lo[1]) / (hi[0] - lo[0])))
    bar = dict(ax=ax, fraction=0.046, pad=0.03)
    vmin, vmax = value_range
    outline = dict(facecolor="none", edgecolor=OUTLINE, linewidth=0.5, joinstyle="round")
    ids = sorted(shapes)
    if field in ("grain", "pressure"):
        coll = PatchCollection([PathPatch(shapes[g].path()) for g in ids], edgecolors=OUTLINE,
                               linewidths=0.5, joinstyle="round", zorder=1)
        if field == "grain":
            size = np.linalg.norm(corners[:, 2] - corners[:, 0], axis=1).max()
            pairs = neighbour_pairs(shapes, size if gap is None else gap, contacts)
            colour = colour_graph(ids, pairs, colours)
            faces = palette_colours(max(colour.values()) + 1)
            if faces is None:
                raise InputError(f"the neighbour graph needs {max(colour.values()) + 1} colours, "
                                 "more than the palettes have")
            value = {g: faces[c] for g, c in colour.items()}
            coll.set_facecolors([value[g] for g in ids])
            ax.add_collection(coll)
        else:
            value = grain_pressure(arr, grain, ids)
            coll.set_array(np.array([value[g] for g in ids]))
            coll.set_cmap("viridis")
            coll.set_clim(vmin, vmax)
            ax.add_collection(coll)
            fig.colorbar(coll, **bar, label="grain pressure −(σxx + σyy)/2 [MPa]")
    else:
        values = arr["pressure"] / 1e6 if field == "point_pressure" else arr["J"]
        xs, tris, at_vertices, offset = [], [], [], 0
        for g in ids:
            s, idx = shapes[g], np.flatnonzero(grain == g)
            xs.append(s.vertices)
            tris.append(s.triangles + offset)
            # The vertex's value: inverse-distance weights of its grain's 4 nearest points.
            at_vertices.append(vertex_values(s, xy[idx], values[idx]))
            offset += len(s.vertices)
        xs = np.concatenate(xs)
        # Interpolated linearly over the triangles (Gouraud shading).
        coll = ax.tripcolor(xs[:, 0], xs[:, 1], np.concatenate(tris), np.concatenate(at_vertices),
                            shading="gouraud", cmap="viridis", vmin=vmin, vmax=vmax, zorder=1)
        coll.set_rasterized(True)  # an image inside PDF and SVG (vector Gouraud: 30 MB of SVG)
        for g in ids:
            ax.add_patch(PathPatch(shapes[g].path(), zorder=2, **outline))
        fig.colorbar(coll, **bar,
                     label="pressure −tr σ/3 [MPa]" if field == "point_pressure" else "J")
        value = None
    if dots:
        ax.plot(xy[:, 0], xy[:, 1], "k.", ms=0.8, zorder=2)
    if network is not None and len(network[1]):
        segs, fn = network
        widths = np.clip(1.5 * fn / fn.mean(), 0.2, 8.0)
        ax.add_collection(LineCollection(segs, linewidths=widths, alpha=0.85, capstyle="round",
                                         colors="black" if field == "grain" else "firebrick",
                                         zorder=3))
    for p, d in walls:
        p = p * 1e3
        span = 2 * np.linalg.norm(hi - lo) + np.linalg.norm(p)
        ax.plot([p[0] - span * d[0], p[0] + span * d[0]], [p[1] - span * d[1], p[1] + span * d[1]],
                "k-", lw=1.5, zorder=4)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    return fig, ax, value


def add_colour_options(ap, range_scope):
    """The colouring options (--field, --colours, --range) of the 2D and 3D snapshot tools;
    range_scope says what shares one colour scale."""
    ap.add_argument("--field", default="grain", choices=FIELDS,
                    help="grain: distinct colours, neighbours never share one; pressure: grain "
                    "pressure; point_pressure, J: per point")
    ap.add_argument("--colours", type=int, default=8,
                    help="palette size for --field grain (more are used only if the neighbour "
                    "graph needs them)")
    ap.add_argument("--range", type=float, nargs=2, default=(None, None), metavar=("LO", "HI"),
                    help="ends of the colour scale (MPa for pressures), " + range_scope)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("folder", help="output folder of `mpmcd run`")
    ap.add_argument("--phi", type=float, nargs="+", required=True, help="solid fractions wanted")
    add_colour_options(ap, "the same for every Φ")
    ap.add_argument("-o", "--output", default=None, help="default <folder>/snapshots")
    ap.add_argument("--dots", action="store_true", help="draw the material points as dots")
    ap.add_argument("--dpi", type=int, default=150)
    ap.add_argument("--squares", action="store_true",
                    help="plain squares of side sqrt(V) instead of the deformed domains")
    ap.add_argument("--forces", action="store_true",
                    help="the contact-force network over the grains (needs [output] grains = true)")
    ap.add_argument("--format", nargs="+", default=["png"], choices=["png", "pdf", "svg"],
                    help="file formats (pdf and svg are vector)")
    ap.add_argument("--no-title", action="store_true", help="no title (Φ, ε, t) over the picture")
    args = ap.parse_args()
    if args.colours < 1:
        ap.error("--colours: expected a positive number")
    try:
        run(args)
    except InputError as e:
        fail(str(e))


def run(args):
    cfg, cols, series = read_run(args.folder)
    if cfg.get("simulation", {}).get("dimension", 2) != 2:
        raise InputError(f"{os.path.join(args.folder, 'input.toml')}: expected a 2D run, found "
                         "[simulation] dimension = 3 (draw it with tools/plot_snapshots_3d.py)")
    name = cfg.get("simulation", {}).get("name", "mpmcd")
    out = args.output or os.path.join(args.folder, "snapshots")
    os.makedirs(out, exist_ok=True)
    times = np.array([t for t, _ in series])
    lam = [m.get("lambda") for m in cfg.get("materials", [])]
    lam_text = f"λ = {lam[0] / 1e6:g} MPa, " if len(set(lam)) == 1 and lam[0] is not None else ""
    cell = cfg.get("grid", {}).get("cell_size")
    gap = float(np.max(cell)) * 1e3 if cell is not None else None
    first = None
    for target in args.phi:
        row = int(np.argmin(np.abs(cols["phi"] - target)))
        k = int(np.argmin(np.abs(times - cols["time"][row])))
        t, vtu = series[k]
        at = int(np.argmin(np.abs(cols["time"] - t)))  # CSV row of the snapshot
        phi, eps = cols["phi"][at], cols["eps"][at]
        pts, arr = read_snapshot(vtu)
        if args.squares:
            arr = {k: v for k, v in arr.items() if not k.startswith("domain_")}
        elif "domain_e1" not in arr and first is None:
            first = read_snapshot(series[0][1])
        corners, how = domains(pts[:, :2] * 1e3, arr, None if args.squares else first)
        forces = None
        if args.forces or args.field == "grain":
            forces = read_forces(args.folder, name, vtu)
            if forces is None and args.forces:
                raise InputError(f"--forces: no {name}_grains_<n>.csv and {name}_forces_<n>.csv "
                                 f"for {vtu} (run with [output] grains = true)")
        stem = f"snapshot_phi{target:.3f}_{args.field}" + ("_forces" if args.forces else "")
        paths = [os.path.join(out, f"{stem}.{ext}") for ext in args.format]
        title = None if args.no_title else f"{lam_text}Φ = {phi:.3f}, ε = {eps:.3f}, t = {t:.4g} s"
        fig, _, _ = draw_snapshot(pts, arr, args.field, corners, wall_segments(cfg, t), gap,
                                  forces[0] if forces else (),
                                  forces[1:] if args.forces else None, args.dots, title,
                                  args.colours, args.range)
        for path in paths:
            fig.savefig(path, dpi=args.dpi, bbox_inches="tight", pad_inches=0.05)
        plt.close(fig)
        print(f"Φ = {target:g}: {os.path.basename(vtu)} (t = {t:.6g} s, Φ = {phi:.4f}, "
              f"ε = {eps:.4f}; {how}) -> {', '.join(paths)}")


if __name__ == "__main__":
    main()
