#!/usr/bin/env python3
"""The same crop of several images of one size, enlarged without filtering and joined
left to right with a black gap (close-ups of `cloud_quality --images` for docs/).

    python3 tools/crop_pair.py OUT.png A.png B.png [C.png ...] --box X,Y,W,H [--zoom 2]

Needs Pillow (`pip install pillow`).
"""

import argparse

from PIL import Image

GAP = 4


def parse_box(text):
    """X,Y,W,H in pixels."""
    x, y, w, h = (int(v) for v in text.split(","))
    return x, y, w, h


def crop_row(frames, box, zoom):
    """The crop `box` of each frame, enlarged `zoom` times, joined with a GAP between;
    a ValueError where the box does not lie inside a frame."""
    x, y, w, h = box
    for f in frames:
        width, height = f.size
        if x < 0 or y < 0 or w <= 0 or h <= 0 or x + w > width or y + h > height:
            raise ValueError(f"box {box} is not inside {width}x{height}")
    zw, zh = w * zoom, h * zoom
    out = Image.new("RGB", (len(frames) * (zw + GAP) - GAP, zh))
    for k, frame in enumerate(frames):
        crop = frame.crop((x, y, x + w, y + h)).resize((zw, zh), Image.NEAREST)
        out.paste(crop, (k * (zw + GAP), 0))
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out")
    parser.add_argument("images", nargs="+")
    parser.add_argument("--box", required=True, help="X,Y,W,H of the crop, pixels")
    parser.add_argument("--zoom", type=int, default=2)
    args = parser.parse_args()
    frames = [Image.open(path).convert("RGB") for path in args.images]
    sizes = {f.size for f in frames}
    if len(sizes) != 1:
        parser.error(f"the images differ in size: {sorted(sizes)}")
    try:
        crop_row(frames, parse_box(args.box), args.zoom).save(args.out)
    except ValueError as e:
        parser.error(str(e))


if __name__ == "__main__":
    main()
