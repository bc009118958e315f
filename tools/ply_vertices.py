"""The vertex rows of a binary little-endian PLY, for the Python tools: the header read
up to the vertices' layout (the first element, scalar properties only), the rows
mapped from the file. Bad input ends the program with a message naming the file.

    from ply_vertices import vertex_rows
    rows = vertex_rows("data/large/lucy_cloud.ply")   # rows["x"], rows["red"], ...
"""
import os
import sys

import numpy as np

# PLY's scalar types as NumPy's little-endian ones.
TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "<i2", "int16": "<i2", "ushort": "<u2", "uint16": "<u2",
    "int": "<i4", "int32": "<i4", "uint": "<u4", "uint32": "<u4",
    "float": "<f4", "float32": "<f4", "double": "<f8", "float64": "<f8",
}


def vertex_layout(f):
    """(count, NumPy dtype of a vertex row, byte offset of the first row) of the open
    PLY `f`, whose first element must be its vertices."""
    if f.readline() != b"ply\n":
        sys.exit(f"{f.name}: not a PLY file")
    count, fields, element = None, [], None
    while True:
        raw = f.readline()
        if not raw:
            sys.exit(f"{f.name}: no end_header")
        words = raw.decode("ascii", "replace").split()
        if words[:1] == ["format"] and words[1:2] != ["binary_little_endian"]:
            sys.exit(f"{f.name}: only binary_little_endian PLY is read here")
        if words[:1] == ["element"]:
            if element is None and (words[1:2] != ["vertex"] or len(words) != 3 or not words[2].isdigit()):
                sys.exit(f"{f.name}: the first element is not its vertices")
            element = words[1]
            if element == "vertex":
                count = int(words[2])
        elif words[:1] == ["property"] and element == "vertex":
            if len(words) != 3 or words[1] not in TYPES:
                sys.exit(f"{f.name}: vertex property {' '.join(words[1:])} is not a scalar")
            fields.append((words[2], TYPES[words[1]]))
        elif words == ["end_header"]:
            if count is None:
                sys.exit(f"{f.name}: no vertex element")
            return count, np.dtype(fields), f.tell()


def vertex_rows(path):
    """The vertex rows of the PLY at `path`, mapped read-only (a structured array)."""
    with open(path, "rb") as f:
        count, dtype, at = vertex_layout(f)
    if os.path.getsize(path) - at < count * dtype.itemsize:
        sys.exit(f"{path}: {count} vertices announced, fewer stored")
    return np.memmap(path, dtype=dtype, mode="r", offset=at, shape=(count,))
