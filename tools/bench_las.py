#!/usr/bin/env python3
"""LAS/LAZ read throughput: spt against laspy with its parallel
lazrs backend, on the same generated files, alternated in one run on one machine.

    python3 tools/bench_las.py [--points 10000000] [--runs 3] [--dir /tmp/spt-las]

Generates (once) a LAS 1.2 point format 3 tile of --points points (a rolling terrain at
UTM coordinates with RGB, intensity, classes and returns) as .las and .laz, with laspy.
Then, --runs times, alternating: `spt info --json` (its load time: read, decode to f64,
rebase to f32 positions with colours, counts by class and return) and laspy.read plus
the scaled x, y, z as f64 arrays, on the LAZ; the same on the LAS, and the time to read
the LAS file's bytes from the page cache. Prints the medians and the ratios.
Needs `pip install "laspy[lazrs]"` and a release build of spt.
"""

import argparse
import json
import os
import statistics
import subprocess
import time

import laspy
import numpy as np


def generate(path_las, path_laz, n):
    rng = np.random.default_rng(14)
    side = int(np.sqrt(n))
    i = np.arange(n)
    x = 500_000.0 + (i % side) * 0.5 + rng.uniform(-0.2, 0.2, n)
    y = 5_400_000.0 + (i // side) * 0.5 + rng.uniform(-0.2, 0.2, n)
    z = 100.0 + 10.0 * np.sin(x / 40.0) * np.cos(y / 55.0) + rng.normal(0, 0.05, n)
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales = np.array([0.01, 0.01, 0.01])
    header.offsets = np.array([500_000.0, 5_400_000.0, 0.0])
    las = laspy.LasData(header)
    las.x, las.y, las.z = x, y, z
    las.intensity = rng.integers(0, 4096, n, dtype=np.uint16)
    las.classification = np.where(z > 105.0, 5, 2).astype(np.uint8)
    las.return_number = np.ones(n, dtype=np.uint8)
    las.number_of_returns = np.ones(n, dtype=np.uint8)
    las.red = (z * 500).astype(np.uint16)
    las.green = np.full(n, 30000, dtype=np.uint16)
    las.blue = las.intensity * 16
    las.gps_time = i.astype(np.float64)
    las.write(path_las)
    las.write(path_laz, laz_backend=laspy.LazBackend.LazrsParallel)


def spt_load(spt, path):
    out = subprocess.run([spt, "info", "--json", path], capture_output=True, text=True, check=True)
    return json.loads(out.stdout)["timing"]["load_seconds"]


def laspy_load(path):
    start = time.perf_counter()
    las = laspy.read(path, laz_backend=laspy.LazBackend.LazrsParallel)
    xyz = [np.asarray(las.x), np.asarray(las.y), np.asarray(las.z)]
    assert len(xyz[0]) == las.header.point_count
    return time.perf_counter() - start


def cache_read(path):
    start = time.perf_counter()
    with open(path, "rb") as f:
        while f.read(1 << 24):
            pass
    return time.perf_counter() - start


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=10_000_000)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--dir", default="/tmp/spt-las")
    parser.add_argument("--spt", default="target/release/spt")
    args = parser.parse_args()
    os.makedirs(args.dir, exist_ok=True)
    las_path = os.path.join(args.dir, f"tile_{args.points}.las")
    laz_path = os.path.join(args.dir, f"tile_{args.points}.laz")
    if not (os.path.exists(las_path) and os.path.exists(laz_path)):
        generate(las_path, laz_path, args.points)
    times = {k: [] for k in ["spt laz", "laspy laz", "spt las", "laspy las", "page cache las"]}
    for _ in range(args.runs):
        times["spt laz"].append(spt_load(args.spt, laz_path))
        times["laspy laz"].append(laspy_load(laz_path))
        times["spt las"].append(spt_load(args.spt, las_path))
        times["laspy las"].append(laspy_load(las_path))
        times["page cache las"].append(cache_read(las_path))
    med = {k: statistics.median(v) for k, v in times.items()}
    size = {p: os.path.getsize(p) / 1e6 for p in (las_path, laz_path)}
    print(f"{args.points:,} points; LAZ {size[laz_path]:.1f} MB, LAS {size[las_path]:.1f} MB; "
          f"laspy {laspy.__version__}; {os.cpu_count()} cores; medians of {args.runs}")
    for k, v in med.items():
        print(f"  {k:15s} {v:7.3f} s  {args.points / v / 1e6:6.2f} M points/s   runs {['%.3f' % t for t in times[k]]}")
    print(f"  laspy / spt on LAZ: {med['laspy laz'] / med['spt laz']:.2f}x; "
          f"on LAS: {med['laspy las'] / med['spt las']:.2f}x; "
          f"spt LAS / page-cache read: {med['spt las'] / med['page cache las']:.1f}x")


if __name__ == "__main__":
    main()
