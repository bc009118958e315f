#!/usr/bin/env python3
"""Where two renders of the same views differ: per view, the share of the drawn pixels
(not the white background in either image) that differ by more than THRESHOLD of 255 in
a channel; with --overlay, view 0 of AFTER with those pixels in magenta.

    python3 tools/changed_pixels.py BEFORE_DIR AFTER_DIR [--overlay OUT.png]

The directories hold `viewN_splats.png` as `cloud_quality --images` writes them. Needs
Pillow and NumPy (`pip install pillow numpy`).
"""

import argparse
from pathlib import Path

import numpy as np
from PIL import Image

THRESHOLD = 24
MAGENTA = (255, 0, 255)


def load(path):
    return np.asarray(Image.open(path).convert("RGB")).astype(np.int16)


def changed(before, after):
    """The changed pixels and the drawn ones, as masks."""
    differ = (np.abs(before - after) > THRESHOLD).any(axis=2)
    drawn = ~((before == 255).all(axis=2) & (after == 255).all(axis=2))
    return differ & drawn, drawn


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", type=Path)
    parser.add_argument("after", type=Path)
    parser.add_argument("--overlay", type=Path)
    args = parser.parse_args()
    views = sorted(args.after.glob("view*_splats.png"))
    if not views:
        parser.error(f"{args.after} holds no view*_splats.png")
    for path in views:
        other = args.before / path.name
        if not other.exists():
            parser.error(f"{other} is missing")
        diff, drawn = changed(load(other), load(path))
        share = 100 * diff.sum() / max(drawn.sum(), 1)
        print(f"{path.stem}: {share:.1f} % of {drawn.sum()} drawn pixels changed")
        if args.overlay and path.name == "view0_splats.png":
            out = load(path).astype(np.uint8)
            out[diff] = MAGENTA
            Image.fromarray(out).save(args.overlay)


if __name__ == "__main__":
    main()
