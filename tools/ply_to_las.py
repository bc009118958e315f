#!/usr/bin/env python3
"""Writes the vertices of a binary little-endian PLY (float x, y, z, optional uchar
red, green, blue) as a LAS file, in slices of 4 M points (laspy), so that a peer that
reads only LAS (PotreeConverter) converts the same points as `spt convert` of the PLY.

    python3 tools/ply_to_las.py data/large/lucy_knot.ply data/large/lucy_knot.las
"""
import sys

import laspy
import numpy as np

TYPES = {"float": "<f4", "float32": "<f4", "double": "<f8", "float64": "<f8",
         "uchar": "u1", "uint8": "u1"}


def vertex_layout(f):
    """(count, numpy dtype of a vertex row, byte offset of the first row)."""
    count, fields, in_vertex = 0, [], False
    while True:
        line = f.readline().decode("ascii").strip()
        if line.startswith("format") and "binary_little_endian" not in line:
            sys.exit(f"{f.name}: only binary_little_endian PLY is read here")
        if line.startswith("element"):
            _, name, n = line.split()
            in_vertex = name == "vertex"
            if in_vertex:
                count = int(n)
        elif line.startswith("property") and in_vertex:
            parts = line.split()
            if parts[1] == "list":
                sys.exit(f"{f.name}: a list property in the vertex element")
            fields.append((parts[2], TYPES[parts[1]]))
        elif line == "end_header":
            return count, np.dtype(fields), f.tell()


def main(src, dst):
    with open(src, "rb") as f:
        count, dtype, at = vertex_layout(f)
    rows = np.memmap(src, dtype=dtype, mode="r", offset=at, shape=(count,))
    colors = all(c in dtype.names for c in ("red", "green", "blue"))
    header = laspy.LasHeader(point_format=2 if colors else 0, version="1.2")
    lo = np.array([rows[k].min() for k in "xyz"], dtype=np.float64)
    hi = np.array([rows[k].max() for k in "xyz"], dtype=np.float64)
    header.offsets = lo
    header.scales = np.maximum((hi - lo) / 2**30, 1e-9)
    with laspy.open(dst, mode="w", header=header) as w:
        step = 1 << 22
        for start in range(0, count, step):
            part = rows[start:start + step]
            points = laspy.ScaleAwarePointRecord.zeros(len(part), header=header)
            points.x, points.y, points.z = part["x"], part["y"], part["z"]
            if colors:
                points.red, points.green, points.blue = (part[c].astype(np.uint16) * 256 for c in ("red", "green", "blue"))
            w.write_points(points)
    print(f"wrote {dst} ({count} points)")


if __name__ == "__main__":
    main(*sys.argv[1:3])
