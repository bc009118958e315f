#!/usr/bin/env python3
"""Another triangulation of the same samples: writes a copy of a triangle mesh (binary
little-endian PLY: float x y z, optional uchar red green blue, triangles) in which every
edge whose quad is nearly cocircular is flipped, one flip per triangle at most.

For such a quad (the two angles facing the edge sum to 180° within --tolerance) both
diagonals are equally good triangulations of the same four samples (both are Delaunay
to within the tolerance), so the flipped mesh is as faithful to the scanned surface as
the original: what differs is only how the triangles interpolate normals and colours
between the samples. Rendering it against the original's supersampled reference
(`cargo run --release --example quality -- MODEL --mesh FLIPPED`) measures how far
apart two equally valid meshes of one scan are.

    python3 tools/alt_triangulation.py IN.ply OUT.ply [--tolerance 20]
"""

import argparse
import os
import sys
import tempfile

import numpy as np


def read_ply(path):
    with open(path, "rb") as f:
        data = f.read()
    end = data.find(b"end_header\n")
    if not data.startswith(b"ply\n") or end < 0:
        sys.exit(f"{path}: not a PLY file (no 'ply' magic or no end_header)")
    header = data[: end + len(b"end_header\n")]
    lines = header.decode("ascii", "replace").splitlines()
    if "format binary_little_endian 1.0" not in lines:
        sys.exit(f"{path}: only binary_little_endian PLY is read here")
    vertex_props, counts, element = [], {}, None
    for line in lines:
        words = line.split()
        if words[:1] == ["element"]:
            element = words[1]
            counts[element] = int(words[2])
        elif words[:1] == ["property"] and element == "vertex":
            vertex_props.append((words[2], words[1]))
    types = {"float": "<f4", "uchar": "u1"}
    if [p for p, _ in vertex_props][:3] != ["x", "y", "z"] or any(t not in types for _, t in vertex_props):
        sys.exit(f"{path}: vertices must be float x y z, then uchar properties")
    vdt = np.dtype([(name, types[t]) for name, t in vertex_props])
    nv, nf = counts.get("vertex", 0), counts.get("face", 0)
    body = len(data) - len(header)
    if nv * vdt.itemsize + nf * 13 != body:
        sys.exit(f"{path}: the body is {body} bytes, not {nv} vertices and {nf} triangles")
    verts = np.frombuffer(data, dtype=vdt, count=nv, offset=len(header))
    fdt = np.dtype([("n", "u1"), ("i", "<i4", (3,))])
    faces = np.frombuffer(data, dtype=fdt, count=nf, offset=len(header) + nv * vdt.itemsize)
    if np.any(faces["n"] != 3) or np.any(faces["i"] < 0) or np.any(faces["i"] >= nv):
        sys.exit(f"{path}: faces must be triangles with indices below {nv}")
    return header, verts, faces["i"].copy()


def angle_at(p, a, b, c):
    """The angle at vertex c of the triangles (a, b, c), radians."""
    u, v = p[a] - p[c], p[b] - p[c]
    cos = np.einsum("ij,ij->i", u, v) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1) + 1e-30)
    return np.arccos(np.clip(cos, -1.0, 1.0))


def flip_cocircular(p, tris, tolerance):
    """Flips nearly cocircular edges (each triangle in one flip at most); returns the
    new triangles and the number of flips."""
    edges = {}
    for t, (a, b, c) in enumerate(tris):
        for u, v, w in ((a, b, c), (b, c, a), (c, a, b)):
            edges[(u, v)] = (t, w)
    used = np.zeros(len(tris), bool)
    out, flips = tris.copy(), 0
    pairs = [(u, v, t, w, edges[(v, u)]) for (u, v), (t, w) in edges.items() if u < v and (v, u) in edges]
    if not pairs:
        return out, 0
    u, v, t1, c, rest = zip(*pairs)
    t2, d = zip(*rest)
    u, v, c, d = map(np.array, (u, v, c, d))
    opposite = angle_at(p, u, v, c) + angle_at(p, u, v, d)
    near = np.abs(opposite - np.pi) < np.radians(tolerance)
    for k in np.flatnonzero(near):
        if used[t1[k]] or used[t2[k]] or c[k] == d[k]:
            continue
        # (u, v, c) and (v, u, d) become (c, d, v) and (d, c, u): same winding.
        old = np.cross(p[v[k]] - p[u[k]], p[c[k]] - p[u[k]]) + np.cross(p[u[k]] - p[v[k]], p[d[k]] - p[v[k]])
        new1 = np.cross(p[d[k]] - p[c[k]], p[v[k]] - p[c[k]])
        new2 = np.cross(p[c[k]] - p[d[k]], p[u[k]] - p[d[k]])
        if old @ new1 <= 0 or old @ new2 <= 0:
            continue
        out[t1[k]] = (c[k], d[k], v[k])
        out[t2[k]] = (d[k], c[k], u[k])
        used[t1[k]] = used[t2[k]] = True
        flips += 1
    return out, flips


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("input")
    parser.add_argument("output")
    parser.add_argument("--tolerance", type=float, default=20.0, help="degrees (default 20)")
    args = parser.parse_args()
    header, verts, tris = read_ply(args.input)
    p = np.stack([verts["x"], verts["y"], verts["z"]], axis=1).astype(np.float64)
    new, flips = flip_cocircular(p, tris, args.tolerance)
    fdt = np.dtype([("n", "u1"), ("i", "<i4", (3,))])
    faces = np.zeros(len(new), fdt)
    faces["n"], faces["i"] = 3, new
    folder = os.path.dirname(os.path.abspath(args.output))
    with tempfile.NamedTemporaryFile(dir=folder, delete=False) as f:
        f.write(header + verts.tobytes() + faces.tobytes())
    os.replace(f.name, args.output)
    print(f"{args.output}: {flips} of {len(tris) * 3 // 2} edges flipped ({flips / max(1, len(tris)) * 200:.1f} % of the triangles changed)")


if __name__ == "__main__":
    main()
