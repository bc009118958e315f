#!/usr/bin/env python3
"""Rows of crops stacked top to bottom with a black gap: each row the same crop of its
images, enlarged without filtering and joined left to right (tools/crop_pair.py).
Every row must come out as wide as the first.

    python3 tools/figure_grid.py OUT.png --row X,Y,W,H,ZOOM A.png B.png ... [--row ...]

Needs Pillow (`pip install pillow`).
"""

import argparse
import sys

from PIL import Image

from crop_pair import GAP, crop_row, parse_box


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out")
    parser.add_argument(
        "--row",
        nargs="+",
        action="append",
        required=True,
        metavar="ARG",
        help="X,Y,W,H,ZOOM of the crop, then the images",
    )
    args = parser.parse_args()
    rows = []
    for spec, *paths in args.row:
        if not paths:
            parser.error(f"row {spec} names no image")
        *box, zoom = (int(v) for v in spec.split(","))
        try:
            frames = [Image.open(p).convert("RGB") for p in paths]
            rows.append(crop_row(frames, parse_box(",".join(map(str, box))), zoom))
        except (ValueError, OSError) as e:
            parser.error(f"row {spec}: {e}")
    widths = {r.width for r in rows}
    if len(widths) != 1:
        parser.error(f"the rows differ in width: {[r.width for r in rows]}")
    out = Image.new("RGB", (rows[0].width, sum(r.height for r in rows) + GAP * (len(rows) - 1)))
    y = 0
    for r in rows:
        out.paste(r, (0, y))
        y += r.height + GAP
    out.save(args.out)


if __name__ == "__main__":
    sys.exit(main())
