#!/usr/bin/python3
"""Pictures of the grains of a 3D run (`[simulation] dimension = 3`): slices and a rendered view.

Usage: plot_snapshots_3d.py <run-folder> (--phi 0.5 0.6 | --time 1e-3 2e-3 | --index 0 -1)
                            [--what slices view] [--axis x y z] [--at 0.5 | --position MM ...]
                            [--thickness MM] [--field grain|pressure|point_pressure|J]
                            [--colours 8] [--range lo hi] [--elev 22] [--azim -58]
                            [-o out-folder] [--dots] [--dpi 150] [--format png pdf svg]
                            [--no-title]

The sibling of tools/plot_snapshots.py (2D) for 3D runs, with its reading (read_run,
read_snapshot), grain outlines (GrainShape) and colouring (colour_graph). Snapshots: for each
--phi, the VTU (series <name>.pvd) nearest in time to the CSV row (<name>.csv) with the nearest Φ
(needs a box of six walls); for each --time, the VTU nearest that time; --index n: the n-th VTU of
the series (negative: from the end).

slices (docs/three_d.md, "Pictures"): one panel per --axis (default x, y and z), the plane normal
to that axis at --at (fractions of the points' bounding box, default 0.5: the mid-planes) or
--position (mm). The points in the slab |x_axis - c| <= thickness/2 (--thickness, default the
median of the points' spacing V^(1/3)) are drawn as the sections of their domains (the
parallelepipeds x + e1 s1 + e2 s2 + e3 s3, s in [-1, 1]^3, of the VTU arrays domain_e1..3; cubes of
side V^(1/3) without them) by the plane, or by the parallel plane through the point when the
plane misses a thin domain; a grain's sections are merged into one filled outline with a thin dark
boundary (GrainShape). Walls cut by the plane are drawn as lines. --dots: the slab's points.

view: the grains' outer points (fewer neighbours within 1.5 spacings than inside the grain, or
an off-centre neighbourhood, in the first snapshot of the series) as discs seen from --elev,
--azim (degrees; y is up), shaded by their outward normal (Lambert) and fading with depth,
painted far to near; the box of the walls (six walls with normals +-x, +-y, +-z) as its twelve
edges.

--field grain: each grain in one colour of a palette of --colours (default 8) in which grains
whose points come within one grid cell (plus their domains) or that are in contact (the
snapshot's <name>_pairs_<n>.csv) never share a colour, the same in every panel and in the view;
pressure: the grain's volume-averaged -tr(sigma)/3 [MPa]; point_pressure, J: per point
(Gouraud-shaded over the sections). The colour scale spans the snapshot's values (all its points,
or grains for pressure), the same in the slices and the view; --range lo hi fixes it.

Writes <out>/slices_<sel>_<field>.<format> and <out>/view_<sel>_<field>.<format>, <sel> phi0.600,
t0.002 or n000004 (the index in the series), for each --format (default png) in <out> (default
<run-folder>/snapshots) and prints what it took and the number of points in each slab. Bad input:
a message naming the file and what was expected, exit code 2. Needs numpy, scipy and matplotlib
(/usr/bin/python3 on Debian 12); no ParaView.
"""
import argparse
import csv
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PatchCollection  # noqa: E402
from matplotlib.colors import Normalize, to_rgb  # noqa: E402
from matplotlib.patches import PathPatch  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plot_snapshots import (OUTLINE, GrainShape, InputError,  # noqa: E402
                            add_colour_options, colour_graph, palette_colours, read_run,
                            read_snapshot, vertex_values)

AXES = "xyz"
# In-plane (horizontal, vertical) axes of the slice normal to each axis: y stays up.
PLANE_AXES = {0: (2, 1), 1: (0, 2), 2: (0, 1)}
SIGNS = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], float)
# The 12 edges of a parallelepiped: corner pairs (rows of SIGNS) differing in one sign.
EDGES = np.array([(a, b) for a in range(8) for b in range(a + 1, 8)
                  if np.sum(SIGNS[a] != SIGNS[b]) == 1])


def fail(msg):
    print(f"plot_snapshots_3d.py: {msg}", file=sys.stderr)
    sys.exit(2)


def half_edges(pts, arr):
    """(n, 3, 3) the domains' half-edges e1, e2, e3 as columns [m]: the VTU arrays domain_e1..3,
    else cubes of side V^(1/3). Returns (edges, how)."""
    if all(f"domain_e{i}" in arr for i in (1, 2, 3)):
        return np.stack([arr[f"domain_e{i}"] for i in (1, 2, 3)], axis=2), "domains of the VTU"
    half = 0.5 * np.cbrt(arr["volume"])
    return half[:, None, None] * np.eye(3)[None], "cubes of side V^(1/3)"


def sections(pts, edges, axis, c):
    """Sections of the domains x + E s, s in [-1, 1]^3, by the plane x_axis = c: (n, 6, 2) convex
    polygons in the plane's (horizontal, vertical) coordinates (PLANE_AXES), counter-clockwise,
    padded to 6 vertices by repeating the last, and (n,) whether the plane cuts the domain. Where
    it does not, the polygon is the section by the parallel plane through the point."""
    corners = pts[:, None, :] + np.einsum("nij,kj->nki", edges, SIGNS)  # (n, 8, 3)
    out = np.zeros((len(pts), 6, 2))
    cut = (corners[:, :, axis].min(axis=1) <= c) & (corners[:, :, axis].max(axis=1) > c)
    for rows, level in ((cut, c), (~cut, None)):
        if not rows.any():
            continue
        cs = corners[rows]
        lev = c if level is not None else pts[rows, axis][:, None]
        d = cs[:, :, axis] - lev  # (m, 8)
        da, db = d[:, EDGES[:, 0]], d[:, EDGES[:, 1]]  # (m, 12)
        cross = (da > 0) != (db > 0)
        t = np.where(cross, da / np.where(cross, da - db, 1.0), 0.0)
        h, v = PLANE_AXES[axis]
        a, b = cs[:, EDGES[:, 0]][:, :, [h, v]], cs[:, EDGES[:, 1]][:, :, [h, v]]
        p = a + t[:, :, None] * (b - a)  # (m, 12, 2)
        count = cross.sum(axis=1, keepdims=True)
        centre = np.sum(p * cross[:, :, None], axis=1) / np.maximum(count, 1)
        ang = np.arctan2(p[:, :, 1] - centre[:, 1:2], p[:, :, 0] - centre[:, 0:1])
        order = np.argsort(np.where(cross, ang, np.inf), axis=1)[:, :6]
        poly = np.take_along_axis(p, order[:, :, None], axis=1)
        k = np.arange(6)[None, :]
        last = np.take_along_axis(poly, np.maximum(count - 1, 0)[:, :, None], axis=1)
        out[rows] = np.where((k < count)[:, :, None], poly, last)
    return out, cut


def outer_points(pts, grain, spacing, reference=None):
    """(n,) bool: the points on the surface of their grain, and (n, 3) their outward normals (unit).
    A point is outer when it has fewer neighbours of its grain within 1.5 spacings than 95 % of the
    grain's most, or when the mean offset of those neighbours is over 0.15 spacings (one-sided).
    The neighbours are found in `reference` (the same points at the first snapshot, where the
    lattice is regular: a squeezed grain's inner points would lose neighbours beyond 1.5 spacings)
    when given, the normal is minus their mean offset now."""
    ref = pts if reference is None else reference
    outer = np.zeros(len(pts), bool)
    normal = np.zeros_like(pts)
    for g in np.unique(grain):
        idx = np.flatnonzero(grain == g)
        x0, x = ref[idx], pts[idx]
        s = np.median(spacing[idx])
        nb = cKDTree(x0).query_ball_point(x0, 1.5 * s)
        count = np.array([len(n) - 1 for n in nb])
        offset0 = np.array([x0[n].mean(axis=0) for n in nb]) - x0
        out = (count < 0.95 * count.max()) | (np.linalg.norm(offset0, axis=1) > 0.15 * s)
        nrm = x - np.array([x[n].mean(axis=0) for n in nb])
        radial = x - x.mean(axis=0)
        weak = np.linalg.norm(nrm, axis=1) < 0.05 * s
        nrm[weak] = radial[weak]
        nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
        outer[idx], normal[idx] = out, nrm
    return outer, normal


def grain_neighbours(pts, grain, outer, reach, contacts=()):
    """Pairs (a, b), a < b, of grains with outer points within `reach` [m] of each other, plus the
    grain-grain `contacts`."""
    pairs = {(min(a, b), max(a, b)) for a, b in contacts if a >= 0 and b >= 0 and a != b}
    idx = np.flatnonzero(outer)
    for i, j in cKDTree(pts[idx]).query_pairs(reach, output_type="ndarray"):
        a, b = grain[idx[i]], grain[idx[j]]
        if a != b:
            pairs.add((min(a, b), max(a, b)))
    return pairs


def read_contacts(folder, name, vtu):
    """Grain-grain pairs [(a, b)] of the snapshot's <name>_pairs_<n>.csv; () without one."""
    m = re.search(r"_(\d+)\.vtu$", vtu)
    path = m and os.path.join(folder, f"{name}_pairs_{m.group(1)}.csv")
    if not path or not os.path.isfile(path):
        return ()
    try:
        with open(path, newline="") as f:
            return [(int(r["body_a"]), int(r["body_b"])) for r in csv.DictReader(f)]
    except (KeyError, TypeError, ValueError) as e:
        raise InputError(f"{path}: expected the columns body_a, body_b (integers): {e!r}")


def walls_at(cfg, cols, t):
    """Each wall as (name, point [m], unit normal) at time t: the input's point moved by the
    CSV's wall_<name>_vx, _vy, _vz (the velocity of each step, as [loading] sets it) when the CSV
    has them, else by the input's velocity."""
    out = []
    times = cols["time"]
    upto = times <= t * (1 + 1e-12) + 1e-300
    for w in cfg.get("walls", []):
        name = w.get("name", "")
        p = np.array(w["point"], float)
        keys = [f"wall_{name}_v{a}" for a in AXES]
        if all(k in cols for k in keys):
            v = np.stack([cols[k] for k in keys], axis=1)
            step = np.diff(times, prepend=times[0])[:, None] * v
            p = p + step[upto].sum(axis=0)
        else:
            p = p + t * np.array(w.get("velocity", [0.0, 0.0, 0.0]), float)
        n = np.array(w["normal"], float)
        out.append((name, p, n / np.linalg.norm(n)))
    return out


def box_of(walls):
    """(lo, hi) [m] of the box of six walls with normals +-x, +-y, +-z, else None."""
    lo, hi = [None] * 3, [None] * 3
    for _, p, n in walls:
        a = int(np.argmax(np.abs(n)))
        if abs(abs(n[a]) - 1) > 1e-9:
            return None
        if n[a] > 0:
            lo[a] = p[a] if lo[a] is None else max(lo[a], p[a])
        else:
            hi[a] = p[a] if hi[a] is None else min(hi[a], p[a])
    if any(v is None for v in lo + hi):
        return None
    return np.array(lo), np.array(hi)


def grain_values(arr, grain, ids):
    """{grain: -tr(sigma)/3 [MPa]} of the volume average of its points' stresses."""
    s, vol = arr["stress"], arr["volume"]
    p = -(s[:, 0] + s[:, 4] + s[:, 8]) / 3
    return {g: float(np.sum(p[grain == g] * vol[grain == g]) / np.sum(vol[grain == g]) / 1e6)
            for g in ids}


def scale(arr, field, value_range):
    """The colour scale's ends of a field: --range, or the range over every point (pressure: every
    grain) of the snapshot, so that the slices and the view share it."""
    grain = arr["grain"].astype(int)
    if field == "pressure":
        vals = np.array(list(grain_values(arr, grain, sorted(set(grain.tolist()))).values()))
    else:
        vals = arr["pressure"] / 1e6 if field == "point_pressure" else arr["J"]
    lo, hi = value_range
    return (float(vals.min()) if lo is None else lo, float(vals.max()) if hi is None else hi)


def colour_grains(pts, arr, grain, outer, cell, contacts, size):
    """{grain: hex colour}, neighbours (grain_neighbours within a cell plus two domain reaches,
    and contacts) never the same; and the pairs used."""
    edges, _ = half_edges(pts, arr)
    reach = 2 * np.linalg.norm(edges, axis=(1, 2)).max() + cell
    pairs = grain_neighbours(pts, grain, outer, reach, contacts)
    colour = colour_graph(sorted(set(grain.tolist())), pairs, size)
    faces = palette_colours(max(colour.values()) + 1)
    if faces is None:
        raise InputError(f"the neighbour graph needs {max(colour.values()) + 1} colours, more than "
                         "the palettes have")
    return {g: faces[c] for g, c in colour.items()}, pairs


def slab(pts, axis, c, thickness):
    """(n,) bool: the points with |x_axis - c| <= thickness / 2 (all in m)."""
    return np.abs(pts[:, axis] - c) <= 0.5 * thickness


def draw_slices(pts, arr, field, planes, thickness, colours, walls=(), dots=False, title=None,
                value_range=(None, None)):
    """The slices figure of one snapshot: positions [m], VTU arrays, `planes` [(axis, c [m])],
    slab `thickness` [m], `colours` {grain: colour} for --field grain. Returns (figure,
    [(axis, c, points in the slab, {grain: GrainShape [mm]})])."""
    grain = arr["grain"].astype(int)
    edges, _ = half_edges(pts, arr)
    box = box_of(walls)
    lo3 = pts.min(axis=0) - np.linalg.norm(edges, axis=(1, 2)).max()
    hi3 = pts.max(axis=0) + np.linalg.norm(edges, axis=(1, 2)).max()
    if box is not None:
        lo3, hi3 = np.minimum(lo3, box[0]), np.maximum(hi3, box[1])
    pad = 0.03 * (hi3 - lo3).max()
    lo3, hi3 = (lo3 - pad) * 1e3, (hi3 + pad) * 1e3
    widths = [hi3[PLANE_AXES[a][0]] - lo3[PLANE_AXES[a][0]] for a, _ in planes]
    height = max(hi3[PLANE_AXES[a][1]] - lo3[PLANE_AXES[a][1]] for a, _ in planes)
    panel = 2.6  # inches per panel height
    bar = field != "grain"
    fig, axs = plt.subplots(1, len(planes), squeeze=False, layout="constrained",
                            figsize=(panel * sum(widths) / height + 0.4 * len(planes) + bar * 0.9,
                                     panel + 0.6 + 0.25 * bool(title)),
                            gridspec_kw=dict(width_ratios=widths))
    axs = axs[0]
    if field == "pressure":
        per_grain = grain_values(arr, grain, sorted(set(grain.tolist())))
    elif field in ("point_pressure", "J"):
        per_point = arr["pressure"] / 1e6 if field == "point_pressure" else arr["J"]
    # The colour scale: value_range (run() passes the snapshot's), else the panels' data.
    drawn, shaded = [], []
    for ax, (axis, c) in zip(axs, planes):
        h, v = PLANE_AXES[axis]
        inside = np.flatnonzero(slab(pts, axis, c, thickness))
        polys, _ = sections(pts[inside], edges[inside], axis, c)
        polys *= 1e3
        g_in = grain[inside]
        shapes = {int(g): GrainShape(polys[g_in == g]) for g in np.unique(g_in)}
        drawn.append((axis, c, len(inside), shapes))
        ids = sorted(shapes)
        patches = [PathPatch(shapes[g].path()) for g in ids]
        if field in ("grain", "pressure"):
            coll = PatchCollection(patches, edgecolors=OUTLINE, linewidths=0.5, joinstyle="round",
                                   zorder=1)
            if field == "grain":
                coll.set_facecolors([colours[g] for g in ids])
            else:
                coll.set_array(np.array([per_grain[g] for g in ids]))
                coll.set_cmap("viridis")
                shaded.append(coll)
            ax.add_collection(coll)
        elif ids:
            xy = pts[inside][:, [h, v]] * 1e3
            xs, tris, vals, offset = [], [], [], 0
            for g in ids:
                s, idx = shapes[g], np.flatnonzero(g_in == g)
                xs.append(s.vertices)
                # Slivers (a corner on a neighbour's edge: heights 1e-4 of a domain) drew stray
                # light lines across the shading: left out (gaps far below a pixel).
                tv = s.vertices[s.triangles]
                edge = np.linalg.norm(tv - np.roll(tv, 1, axis=1), axis=2).max(axis=1)
                height = np.cross(tv[:, 1] - tv[:, 0], tv[:, 2] - tv[:, 0]) / edge
                tris.append(s.triangles[height > 1e-2 * np.median(edge)] + offset)
                vals.append(vertex_values(s, xy[idx], per_point[inside][idx]))
                offset += len(s.vertices)
            xs = np.concatenate(xs)
            coll = ax.tripcolor(xs[:, 0], xs[:, 1], np.concatenate(tris), np.concatenate(vals),
                                shading="gouraud", cmap="viridis", zorder=1)
            coll.set_rasterized(True)
            shaded.append(coll)
            ax.add_collection(PatchCollection(patches, facecolor="none", edgecolor=OUTLINE,
                                              linewidths=0.5, joinstyle="round", zorder=2))
        if dots:
            ax.plot(pts[inside, h] * 1e3, pts[inside, v] * 1e3, "k.", ms=0.8, zorder=2)
        if box is not None:  # the box's section: a rectangle
            ax.add_patch(plt.Rectangle((box[0][h] * 1e3, box[0][v] * 1e3),
                                       (box[1][h] - box[0][h]) * 1e3,
                                       (box[1][v] - box[0][v]) * 1e3,
                                       fill=False, edgecolor="black", lw=1.5, zorder=4))
        for _, p, n in walls if box is None else ():
            # The wall's trace in the plane: n_h u + n_v w = n . p - n_axis c.
            nh, nv = n[h], n[v]
            if np.hypot(nh, nv) < 1e-9:
                continue
            rhs = (n @ p - n[axis] * c) * 1e3
            q = np.array([nh, nv]) * rhs / (nh ** 2 + nv ** 2)
            d = np.array([-nv, nh]) / np.hypot(nh, nv)
            span = 4 * np.linalg.norm(hi3 - lo3) + np.linalg.norm(q)
            ax.plot([q[0] - span * d[0], q[0] + span * d[0]], [q[1] - span * d[1],
                                                               q[1] + span * d[1]],
                    "k-", lw=1.5, zorder=4)
        ax.set_xlim(lo3[h], hi3[h])
        ax.set_ylim(lo3[v], hi3[v])
        ax.set_aspect("equal")
        ax.set_xlabel(f"{AXES[h]} [mm]")
        ax.set_ylabel(f"{AXES[v]} [mm]")
        ax.set_title(f"{AXES[axis]} = {c * 1e3:.3g} mm ({len(inside)} points)", fontsize=9)
    if shaded:
        vals = np.concatenate([np.asarray(s.get_array()).ravel() for s in shaded])
        vmin = value_range[0] if value_range[0] is not None else (vals.min() if len(vals) else 0)
        vmax = value_range[1] if value_range[1] is not None else (vals.max() if len(vals) else 1)
        for s in shaded:
            s.set_clim(vmin, vmax)
        label = {"pressure": "grain pressure −tr σ/3 [MPa]",
                 "point_pressure": "pressure −tr σ/3 [MPa]", "J": "J"}[field]
        fig.colorbar(shaded[0], ax=list(axs), fraction=0.04, pad=0.02, label=label)
    if title:
        fig.suptitle(title, fontsize=10)
    return fig, drawn


def draw_view(pts, arr, field, colours, walls=(), elev=22.0, azim=-58.0, title=None,
              value_range=(None, None), outer=None):
    """The rendered view of one snapshot: the grains' outer points as discs, shaded, far to near;
    the walls' box. Plot axes (X, Y, Z) = (z, x, y) [mm], so that y is up (right-handed).
    Returns (figure, number of points drawn)."""
    grain = arr["grain"].astype(int)
    spacing = np.cbrt(arr["volume"])
    if outer is None:
        outer = outer_points(pts, grain, spacing)
    keep, normal = outer
    perm = [2, 0, 1]
    x = pts[keep][:, perm] * 1e3
    nrm = normal[keep][:, perm]
    g = grain[keep]
    if field == "grain":
        base = np.array([to_rgb(colours[k]) for k in g])
        mappable = None
    else:
        if field == "pressure":
            per = grain_values(arr, grain, sorted(set(g.tolist())))
            vals = np.array([per[k] for k in g])
        else:
            vals = (arr["pressure"] / 1e6 if field == "point_pressure" else arr["J"])[keep]
        lo = value_range[0] if value_range[0] is not None else vals.min()
        hi = value_range[1] if value_range[1] is not None else vals.max()
        mappable = plt.cm.ScalarMappable(Normalize(lo, hi), "viridis")
        base = mappable.to_rgba(vals)[:, :3]
    e, a = np.radians(elev), np.radians(azim)
    eye = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    # Light from over the viewer's left shoulder.
    up = np.array([0.0, 0.0, 1.0]) - np.sin(e) * eye
    left = np.cross(up / np.linalg.norm(up), eye)
    light = eye + 0.6 * up / np.linalg.norm(up) + 0.4 * left
    light /= np.linalg.norm(light)
    lambert = np.clip(nrm @ light, 0, 1)
    depth = x @ eye
    near = (depth - depth.min()) / max(np.ptp(depth), 1e-300)  # 1 nearest, 0 farthest
    # Fields keep more of their colour (the colour scale is read from it).
    ambient = 0.5 if field == "grain" else 0.6
    shade = (ambient + (1 - ambient) * lambert) * (0.75 + 0.25 * near)
    rgb = np.clip(base * shade[:, None], 0, 1)
    order = np.argsort(depth)  # far to near
    box = box_of(walls)
    lo3, hi3 = x.min(axis=0), x.max(axis=0)
    if box is not None:
        lo3 = np.minimum(lo3, box[0][perm] * 1e3)
        hi3 = np.maximum(hi3, box[1][perm] * 1e3)
    fig = plt.figure(figsize=(5.4, 5.0))
    ax = fig.add_subplot(projection="3d", computed_zorder=False)
    if mappable is None:  # room on the right for the vertical axis' label
        fig.set_size_inches(6.0, 5.0)
        ax.set_position([0.0, 0.0, 0.86, 1.0])
    ax.view_init(elev=elev, azim=azim)
    ax.set_box_aspect(hi3 - lo3, zoom=0.9)  # (zoom: room for the axis labels)
    # The disc's diameter: 1.7 spacings, the box's diagonal spanning about 0.93 of the axes' width.
    width_pt = 0.93 * ax.get_position().width * fig.get_figwidth() * 72
    size = width_pt * np.median(spacing[keep]) * 1e3 / np.linalg.norm(hi3 - lo3)
    ax.scatter(x[order, 0], x[order, 1], x[order, 2], c=rgb[order], s=(1.7 * size) ** 2,
                    depthshade=False, edgecolors="none", marker="o", zorder=2)
    if box is not None:
        blo, bhi = box[0][perm] * 1e3, box[1][perm] * 1e3
        corners = np.array([[bhi[i] if s > 0 else blo[i] for i, s in enumerate(sg)]
                            for sg in SIGNS])
        far = int(np.argmin(corners @ eye))
        for i, j in EDGES:
            behind = far in (i, j)
            ax.plot(*corners[[i, j]].T, color="0.55" if behind else "0.15",
                    lw=0.6 if behind else 0.9, ls="--" if behind else "-",
                    zorder=1 if behind else 3)
    ax.set_rasterization_zorder(2.5)  # the discs (and hidden edges): an image in PDF and SVG
    ax.set_xlim(lo3[0], hi3[0])
    ax.set_ylim(lo3[1], hi3[1])
    ax.set_zlim(lo3[2], hi3[2])
    ax.set_xlabel("z [mm]", labelpad=-2)
    ax.set_ylabel("x [mm]", labelpad=-2)
    ax.set_zlabel("y [mm]", labelpad=-2)
    ax.tick_params(labelsize=7, pad=0)
    ax.grid(False)
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.pane.set_facecolor((1, 1, 1, 0))
        axis.pane.set_edgecolor("0.85")
    if mappable is not None:
        fig.colorbar(mappable, ax=ax, fraction=0.035, pad=0.12, shrink=0.6,
                     label={"pressure": "grain pressure −tr σ/3 [MPa]",
                            "point_pressure": "pressure −tr σ/3 [MPa]", "J": "J"}[field])
    if title:
        ax.set_title(title, fontsize=10)
    return fig, int(keep.sum())


def choose(args, cols, series):
    """[(label for file names, index in the series, what was asked)] of the snapshots asked."""
    times = np.array([t for t, _ in series])
    out = []
    if args.phi:
        for target in args.phi:
            row = int(np.argmin(np.abs(cols["phi"] - target)))
            out.append((f"phi{target:.3f}", int(np.argmin(np.abs(times - cols["time"][row]))),
                        f"Φ = {target:g}"))
    elif args.time:
        for t in args.time:
            out.append((f"t{t:g}", int(np.argmin(np.abs(times - t))), f"t = {t:g} s"))
    else:
        for i in args.index:
            if not -len(series) <= i < len(series):
                raise InputError(f"--index {i}: the series has {len(series)} snapshots "
                                 f"(expected -{len(series)} to {len(series) - 1})")
            out.append((f"n{i % len(series):06d}", i % len(series), f"index {i}"))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("folder", help="output folder of `mpmcd run` (a 3D run)")
    sel = ap.add_mutually_exclusive_group(required=True)
    sel.add_argument("--phi", type=float, nargs="+", help="solid fractions wanted (needs a box)")
    sel.add_argument("--time", type=float, nargs="+", help="times wanted [s]")
    sel.add_argument("--index", type=int, nargs="+",
                     help="snapshots by their place in the .pvd series (negative: from the end)")
    ap.add_argument("--what", nargs="+", default=["slices", "view"], choices=["slices", "view"])
    ap.add_argument("--axis", nargs="+", default=list(AXES), choices=list(AXES),
                    help="normals of the slices' planes")
    where = ap.add_mutually_exclusive_group()
    where.add_argument("--at", type=float, nargs="+", default=[0.5],
                       help="planes' positions as fractions of the points' bounding box (one, or "
                       "one per --axis)")
    where.add_argument("--position", type=float, nargs="+",
                       help="planes' positions [mm] (one, or one per --axis)")
    ap.add_argument("--thickness", type=float, default=None,
                    help="slab thickness [mm] (default: the median point spacing V^(1/3))")
    add_colour_options(ap, "the same for every picture")
    ap.add_argument("--elev", type=float, default=22.0, help="view: elevation [deg]")
    ap.add_argument("--azim", type=float, default=-58.0, help="view: azimuth [deg]")
    ap.add_argument("-o", "--output", default=None, help="default <folder>/snapshots")
    ap.add_argument("--dots", action="store_true", help="slices: draw the slab's points as dots")
    ap.add_argument("--dpi", type=int, default=150)
    ap.add_argument("--format", nargs="+", default=["png"], choices=["png", "pdf", "svg"],
                    help="file formats (pdf and svg are vector, the view's discs an image)")
    ap.add_argument("--no-title", action="store_true", help="no title (Φ, ε, t) over the picture")
    args = ap.parse_args()
    if args.colours < 1:
        ap.error("--colours: expected a positive number")
    places = args.position if args.position is not None else args.at
    if len(places) not in (1, len(args.axis)):
        ap.error(f"--at/--position: expected 1 or {len(args.axis)} values (one per --axis)")
    if args.thickness is not None and args.thickness <= 0:
        ap.error("--thickness: expected a positive number [mm]")
    try:
        run(args)
    except InputError as e:
        fail(str(e))


def run(args):
    path = os.path.join(args.folder, "input.toml")
    cfg, cols, series = read_run(args.folder, ("time", "phi") if args.phi else ("time",),
                                 ("phi", "eps"))
    if cfg.get("simulation", {}).get("dimension", 2) != 3:
        raise InputError(f"{path}: expected a 3D run ([simulation] dimension = 3); draw 2D runs "
                         "with tools/plot_snapshots.py")
    names = [w.get("name", "") for w in cfg.get("walls", [])]
    wall_cols = [f"wall_{n}_v{a}" for n in names for a in AXES]
    if wall_cols:  # the walls' velocities of each step (the names are in the input)
        cols.update(read_run(args.folder, ("time",), wall_cols)[1])
    name = cfg.get("simulation", {}).get("name", "mpmcd")
    out = args.output or os.path.join(args.folder, "snapshots")
    os.makedirs(out, exist_ok=True)
    cell = float(cfg.get("grid", {}).get("cell_size", 0.0))
    first = None  # the first snapshot (positions, arrays): the reference of the outer points
    for label, k, asked in choose(args, cols, series):
        t, vtu = series[k]
        pts, arr = read_snapshot(vtu)
        grain = arr["grain"].astype(int)
        at = int(np.argmin(np.abs(cols["time"] - t)))  # CSV row of the snapshot
        state = f"t = {t:.4g} s"
        if "phi" in cols:
            state = f"Φ = {cols['phi'][at]:.3f}, " + (f"ε = {cols['eps'][at]:.3f}, "
                                                       if "eps" in cols else "") + state
        title = None if args.no_title else state
        walls = walls_at(cfg, cols, t)
        spacing = np.cbrt(arr["volume"])
        if first is None:
            first = read_snapshot(series[0][1])
        same = len(first[0]) == len(pts) and np.array_equal(first[1]["grain"], arr["grain"])
        outer = outer_points(pts, grain, spacing, first[0] if same else None)
        colours = None
        value_range = args.range
        if args.field == "grain":
            colours, pairs = colour_grains(pts, arr, grain, outer[0], cell,
                                           read_contacts(args.folder, name, vtu), args.colours)
        else:
            value_range = scale(arr, args.field, args.range)
        written, notes = [], []
        if "slices" in args.what:
            lo, hi = pts.min(axis=0), pts.max(axis=0)
            planes = []
            for i, ax_name in enumerate(args.axis):
                a = AXES.index(ax_name)
                if args.position is not None:
                    c = args.position[i if len(args.position) > 1 else 0] * 1e-3
                else:
                    # Moved by a quarter spacing: a lattice's layers (at the mid-plane or
                    # half a spacing from it) are then never on the slab's faces.
                    f = args.at[i if len(args.at) > 1 else 0]
                    c = lo[a] + f * (hi[a] - lo[a]) + 0.25 * float(np.median(spacing))
                planes.append((a, c))
            thickness = (args.thickness * 1e-3 if args.thickness is not None
                         else float(np.median(spacing)))
            fig, drawn = draw_slices(pts, arr, args.field, planes, thickness, colours, walls,
                                     args.dots, title, value_range)
            stem = os.path.join(out, f"slices_{label}_{args.field}")
            for ext in args.format:
                fig.savefig(f"{stem}.{ext}", dpi=args.dpi, bbox_inches="tight", pad_inches=0.05)
                written.append(f"{stem}.{ext}")
            plt.close(fig)
            notes += [f"{AXES[a]} = {c:.6g} m: {n} points in the slab of {thickness:.4g} m, "
                      f"{len(shapes)} grains" for a, c, n, shapes in drawn]
        if "view" in args.what:
            fig, n = draw_view(pts, arr, args.field, colours, walls, args.elev, args.azim, title,
                               value_range, outer)
            stem = os.path.join(out, f"view_{label}_{args.field}")
            for ext in args.format:
                fig.savefig(f"{stem}.{ext}", dpi=args.dpi, bbox_inches="tight", pad_inches=0.05)
                written.append(f"{stem}.{ext}")
            plt.close(fig)
            notes.append(f"view: {n} outer points of {len(pts)}")
        print(f"{asked}: {os.path.basename(vtu)} ({state}; {half_edges(pts, arr)[1]}"
              + (f"; {len(set(colours.values()))} colours, {len(pairs)} neighbour pairs"
                 if colours else "") + ")\n  " + "\n  ".join(notes) + "\n  -> "
              + ", ".join(written))


if __name__ == "__main__":
    main()
