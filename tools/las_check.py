#!/usr/bin/env python3
"""Checks spt's LAS/LAZ reader against laspy (with its lazrs backend) on the same files:
the point count, the bounding box of the scaled coordinates (exactly, as f64), the
counts by ASPRS class and by return number, and the intensity range must agree.

    python3 tools/las_check.py [--spt target/release/spt] FILE.las|laz...

Exits 1 and says what differs when anything does. Needs `pip install "laspy[lazrs]"`.
"""

import argparse
import json
import subprocess
import sys

import laspy
import numpy as np


def laspy_view(path):
    las = laspy.read(path)
    xyz = np.stack([np.asarray(las.x), np.asarray(las.y), np.asarray(las.z)], axis=1)
    hist = lambda a: [[int(v), int(n)] for v, n in zip(*np.unique(np.asarray(a), return_counts=True))]
    return {
        "points": len(las.points),
        "min": xyz.min(axis=0).tolist(),
        "max": xyz.max(axis=0).tolist(),
        "by_class": hist(las.classification),
        "by_return": hist(las.return_number),
        "intensity": [int(np.min(las.intensity)), int(np.max(las.intensity))],
    }


def spt_view(spt, path):
    out = subprocess.run([spt, "info", "--json", path], capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"{path}: spt info failed: {out.stderr.strip()}")
    info = json.loads(out.stdout)
    las = info["las"]
    return {
        "points": las["points"],
        "min": info["bounds"]["min"],
        "max": info["bounds"]["max"],
        "by_class": las["by_class"],
        "by_return": las["by_return"],
        "intensity": las["intensity"],
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spt", default="target/release/spt")
    parser.add_argument("files", nargs="+")
    args = parser.parse_args()
    failed = False
    for path in args.files:
        ours, theirs = spt_view(args.spt, path), laspy_view(path)
        diff = [k for k in theirs if ours[k] != theirs[k]]
        for k in diff:
            print(f"{path}: {k}: spt {ours[k]} != laspy {theirs[k]}")
        failed |= bool(diff)
        if not diff:
            print(f"{path}: {ours['points']} points, bounds {ours['min']} – {ours['max']}, "
                  f"{len(ours['by_class'])} classes, {len(ours['by_return'])} return numbers: "
                  f"equal to laspy {laspy.__version__}")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
