#!/usr/bin/env python3
"""Writes the vertices of a binary little-endian PLY (x, y, z, optional uchar red,
green, blue; tools/ply_vertices.py reads them) as a LAS file, in slices of 4 M points (laspy), so that a peer that
reads only LAS (PotreeConverter) converts the same points as `spt convert` of the PLY.

    python3 tools/ply_to_las.py data/large/lucy_knot.ply data/large/lucy_knot.las
"""
import sys

import laspy
import numpy as np

from ply_vertices import vertex_rows

def main(src, dst):
    rows = vertex_rows(src)
    count, dtype = len(rows), rows.dtype
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
