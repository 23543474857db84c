#!/usr/bin/python3
"""Reads the point-cloud .vtu files written by mpmcd (raw appended binary) into numpy arrays.

Usage as a module: `points, arrays = read_vtu(path)` (and `write_vtu(path, points, arrays)`, the
same layout, for tests); as a script: `vtu_points.py file.vtu` prints
the array names and ranges.
"""
import re
import sys

import numpy as np

_TYPES = {"Float64": np.float64, "Int32": np.int32, "Int64": np.int64, "UInt8": np.uint8}


def read_vtu(path):
    """Returns (points (n, 3) array, dict name -> array) of an mpmcd .vtu file."""
    with open(path, "rb") as f:
        raw = f.read()
    start = raw.index(b'<AppendedData encoding="raw">')
    blob = raw[raw.index(b"_", start) + 1:]
    header = raw[:start].decode()
    arrays, points = {}, None
    for m in re.finditer(r"<DataArray ([^>]*)/>", header):
        attrs = dict(re.findall(r'(\w+)="([^"]*)"', m.group(1)))
        off = int(attrs["offset"])
        nbytes = int(np.frombuffer(blob[off:off + 8], dtype=np.uint64)[0])
        data = np.frombuffer(blob[off + 8:off + 8 + nbytes], dtype=_TYPES[attrs["type"]])
        ncomp = int(attrs.get("NumberOfComponents", "1"))
        if ncomp > 1:
            data = data.reshape(-1, ncomp)
        if "Name" in attrs:
            arrays[attrs["Name"]] = data
        else:
            points = data
    return points, arrays


def write_vtu(path, points, arrays):
    """Writes points (n, 3) and {name: array} (float64, or int32 for integer arrays; (n,) or
    (n, components)) as a vertex cloud in mpmcd's layout (raw appended data)."""
    n = len(points)
    head, blob = [], b""

    def block(a):
        return np.uint64(a.nbytes).tobytes() + a.tobytes()

    for name, a in arrays.items():
        a = np.ascontiguousarray(a, np.int32 if np.issubdtype(a.dtype, np.integer) else np.float64)
        kind = "Int32" if a.dtype == np.int32 else "Float64"
        comps = 1 if a.ndim == 1 else a.shape[1]
        head.append(f'<DataArray type="{kind}" Name="{name}" NumberOfComponents="{comps}" '
                    f'format="appended" offset="{len(blob)}"/>')
        blob += block(a)
    pos = ('<DataArray type="Float64" NumberOfComponents="3" format="appended" '
           f'offset="{len(blob)}"/>')
    blob += block(np.ascontiguousarray(points, np.float64))
    text = ('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" '
            'byte_order="LittleEndian" header_type="UInt64">\n<UnstructuredGrid>\n'
            f'<Piece NumberOfPoints="{n}" NumberOfCells="0">\n<PointData>\n' + "\n".join(head)
            + f"\n</PointData>\n<Points>\n{pos}\n</Points>\n</Piece>\n</UnstructuredGrid>\n"
            '<AppendedData encoding="raw">\n_')
    with open(path, "wb") as f:
        f.write(text.encode() + blob + b"\n</AppendedData>\n</VTKFile>\n")


if __name__ == "__main__":
    pts, arr = read_vtu(sys.argv[1])
    print(f"{len(pts)} points, x in [{pts[:, 0].min():.6g}, {pts[:, 0].max():.6g}], "
          f"y in [{pts[:, 1].min():.6g}, {pts[:, 1].max():.6g}]")
    for k, v in arr.items():
        print(f"  {k}: shape {v.shape}, range [{v.min():.6g}, {v.max():.6g}]")
