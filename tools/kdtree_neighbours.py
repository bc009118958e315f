#!/usr/bin/env python3
"""SciPy's k-d tree as a peer for the neighbour search of `spt convert`: reads the
vertices of a binary little-endian PLY_FILE (scalar properties, x, y and z among
them), builds a `cKDTree` over them and queries every point's K nearest (the
point itself included, as spt's neighbourhoods of K = 24 are) on all cores. Prints
the points, the read, build and query times.

    pip install scipy
    python3 tools/kdtree_neighbours.py PLY_FILE [K]
"""
import sys
import time

import numpy as np
from numpy.lib.recfunctions import structured_to_unstructured
from scipy.spatial import cKDTree

from ply_vertices import vertex_rows


def vertices(path):
    """The finite x, y, z of the vertices of the PLY at `path`
    (tools/ply_vertices.py), and the count of all of them."""
    rows = vertex_rows(path)
    if not all(axis in rows.dtype.names for axis in "xyz"):
        sys.exit(f"{path}: vertices without x, y and z")
    # A view of the rows where x, y and z are floats one after another.
    points = structured_to_unstructured(rows[["x", "y", "z"]])
    # As spt's loaders do, a vertex with a coordinate that is not finite is dropped.
    finite = np.isfinite(points)
    if finite.all():
        return points, len(rows)
    return points[finite.all(axis=1)], len(rows)


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    path, k = sys.argv[1], int(sys.argv[2]) if len(sys.argv) == 3 else 24
    start = time.perf_counter()
    points, count = vertices(path)
    read = time.perf_counter()
    tree = cKDTree(points)
    built = time.perf_counter()
    tree.query(points, k=k, workers=-1)
    queried = time.perf_counter()
    print(
        f"{len(points)} points ({count - len(points)} not finite, dropped), "
        f"read {read - start:.2f} s, tree {built - read:.2f} s, "
        f"{k} nearest of every point {queried - built:.2f} s"
    )


if __name__ == "__main__":
    main()
