#!/usr/bin/env python3
"""SciPy's k-d tree as a peer for the neighbour search of `spt convert`: reads the
vertices of a binary little-endian PLY_FILE (x, y, z as its first three float
properties), builds a `cKDTree` over them and queries every point's K nearest (the
point itself included, as spt's neighbourhoods of K = 24 are) on all cores. Prints
the points, the read, build and query times.

    pip install scipy
    python3 tools/kdtree_neighbours.py PLY_FILE [K]
"""
import sys
import time

import numpy as np
from scipy.spatial import cKDTree


def vertices(path):
    """The vertex positions of a binary little-endian PLY whose vertices come first
    and hold only float properties, x, y and z first."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.find(b"end_header\n")
    if end < 0:
        sys.exit(f"{path}: no PLY header")
    header = data[:end].decode("ascii", "replace").splitlines()
    if "format binary_little_endian 1.0" not in header:
        sys.exit(f"{path}: not a binary little-endian PLY")
    count, properties = None, []
    for line in header:
        words = line.split()
        if words[:2] == ["element", "vertex"]:
            count = int(words[2])
        elif words[:1] == ["element"] and count is not None:
            break
        elif words[:1] == ["property"] and count is not None:
            properties.append(words)
    if count is None or [p[2] for p in properties[:3]] != ["x", "y", "z"]:
        sys.exit(f"{path}: no vertex element starting with x, y, z")
    if any(p[1] != "float" for p in properties):
        sys.exit(f"{path}: vertex properties other than float")
    width = len(properties)
    start = end + len(b"end_header\n")
    if len(data) - start < 4 * width * count:
        sys.exit(f"{path}: {count} vertices announced, fewer stored")
    rows = np.frombuffer(data, dtype="<f4", count=width * count, offset=start)
    return rows.reshape(count, width)[:, :3]


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    path, k = sys.argv[1], int(sys.argv[2]) if len(sys.argv) == 3 else 24
    start = time.perf_counter()
    points = vertices(path)
    read = time.perf_counter()
    tree = cKDTree(points)
    built = time.perf_counter()
    tree.query(points, k=k, workers=-1)
    queried = time.perf_counter()
    print(
        f"{len(points)} points, read {read - start:.2f} s, tree {built - read:.2f} s, "
        f"{k} nearest of every point {queried - built:.2f} s"
    )


if __name__ == "__main__":
    main()
