#!/usr/bin/python3
"""Reads the point-cloud .vtu files written by mpmcd (raw appended binary) into numpy arrays.

Usage as a module: `points, arrays = read_vtu(path)`; as a script: `vtu_points.py file.vtu` prints
the array names and ranges.
"""
import re
import sys

import numpy as np

_TYPES = {"Float64": np.float64, "Int32": np.int32, "Int64": np.int64, "UInt8": np.uint8}


def read_vtu(path):
    """Returns (points (n, 3) array, dict name -> array) of an mpmcd .vtu file."""
    raw = open(path, "rb").read()
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


if __name__ == "__main__":
    pts, arr = read_vtu(sys.argv[1])
    print(f"{len(pts)} points, x in [{pts[:, 0].min():.6g}, {pts[:, 0].max():.6g}], "
          f"y in [{pts[:, 1].min():.6g}, {pts[:, 1].max():.6g}]")
    for k, v in arr.items():
        print(f"  {k}: shape {v.shape}, range [{v.min():.6g}, {v.max():.6g}]")
