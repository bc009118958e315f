#!/usr/bin/env python3
"""Open3D's normal estimation on a cloud, as a peer for the neighbourhood work of
`spt convert`: reads PLY_FILE and fits each point's normal to its K nearest
neighbours (`estimate_normals` with `KDTreeSearchParamKNN`, a k-d tree and a
covariance per point, on all cores). Prints the points, the read and the fit times.

    pip install open3d
    python3 tools/open3d_normals.py PLY_FILE [K]
"""
import sys
import time

import open3d as o3d


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    path, k = sys.argv[1], int(sys.argv[2]) if len(sys.argv) == 3 else 24
    start = time.perf_counter()
    cloud = o3d.io.read_point_cloud(path)
    if not cloud.has_points():
        sys.exit(f"{path}: no points read")
    read = time.perf_counter()
    cloud.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(k))
    fitted = time.perf_counter()
    print(f"{len(cloud.points)} points, read {read - start:.2f} s, normals (k = {k}) {fitted - read:.2f} s")


if __name__ == "__main__":
    main()
