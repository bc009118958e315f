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
from scipy.spatial import cKDTree


# PLY scalar types as NumPy's little-endian ones.
TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "<i2", "int16": "<i2", "ushort": "<u2", "uint16": "<u2",
    "int": "<i4", "int32": "<i4", "uint": "<u4", "uint32": "<u4",
    "float": "<f4", "float32": "<f4", "double": "<f8", "float64": "<f8",
}


def vertices(path):
    """The finite x, y, z of the vertices of a binary little-endian PLY whose first
    element is its vertices, with scalar properties only; and the count of all of them."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.find(b"end_header\n")
    if end < 0:
        sys.exit(f"{path}: no PLY header")
    header = data[:end].decode("ascii", "replace").splitlines()
    if "format binary_little_endian 1.0" not in header:
        sys.exit(f"{path}: not a binary little-endian PLY")
    first = next((k for k, line in enumerate(header) if line.split()[:1] == ["element"]), None)
    words = header[first].split() if first is not None else []
    if words[:2] != ["element", "vertex"] or len(words) != 3 or not words[2].isdigit():
        sys.exit(f"{path}: the first element is not its vertices")
    count, fields = int(words[2]), []
    for line in header[first + 1:]:
        words = line.split()
        if words[:1] != ["property"]:
            break
        if words[1] not in TYPES:
            sys.exit(f"{path}: vertex property {' '.join(words[1:])} is not a scalar")
        fields.append((words[2], TYPES[words[1]]))
    names = [name for name, _ in fields]
    if not all(axis in names for axis in "xyz"):
        sys.exit(f"{path}: vertices without x, y and z")
    rows = np.dtype(fields)
    start = end + len(b"end_header\n")
    if len(data) - start < rows.itemsize * count:
        sys.exit(f"{path}: {count} vertices announced, fewer stored")
    offsets = [rows.fields[axis][1] for axis in "xyz"]
    if [rows.fields[axis][0] for axis in "xyz"] == [np.dtype("<f4")] * 3 and offsets == [
        offsets[0] + 4 * k for k in range(3)
    ]:
        # Consecutive floats: a view of the file's rows, as the tree takes them.
        points = np.ndarray((count, 3), "<f4", data, start + offsets[0], (rows.itemsize, 4))
    else:
        table = np.frombuffer(data, dtype=rows, count=count, offset=start)
        points = np.column_stack([table[axis].astype(np.float64) for axis in "xyz"])
    # As spt's loaders do, a vertex with a coordinate that is not finite is dropped.
    if np.isfinite(points).all():
        return points, count
    return points[np.isfinite(points).all(axis=1)], count


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
        f"{len(points)} points ({count - len(points)} not finite, dropped), read {read - start:.2f} s, tree {built - read:.2f} s, "
        f"{k} nearest of every point {queried - built:.2f} s"
    )


if __name__ == "__main__":
    main()
