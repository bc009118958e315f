#!/usr/bin/env python3
"""One picture of a model in several display modes, left to right, each drawn by
`spt render` with the same camera (the mode pictures of docs/).

    python3 tools/mode_strip.py MODEL OUT.png --modes shaded,classification,intensity \\
        [--size 640x360] [--orbit AZ,EL,DIST] [--spt target/release/spt]

Needs Pillow (`pip install pillow`) to join the frames.
"""

import argparse
import os
import subprocess
import tempfile

from PIL import Image


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("model")
    parser.add_argument("out")
    parser.add_argument("--modes", default="shaded,edl,elevation")
    parser.add_argument("--size", default="640x360")
    parser.add_argument("--orbit", default=None)
    parser.add_argument("--spt", default="target/release/spt")
    args = parser.parse_args()
    frames = []
    with tempfile.TemporaryDirectory() as tmp:
        for mode in args.modes.split(","):
            path = os.path.join(tmp, f"{mode}.png")
            cmd = [args.spt, "render", args.model, "-o", path, "--size", args.size, "--mode", mode]
            if args.orbit:
                cmd += ["--orbit", args.orbit]
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
            frames.append(Image.open(path).convert("RGB"))
    width = sum(f.width for f in frames)
    strip = Image.new("RGB", (width, max(f.height for f in frames)), "white")
    x = 0
    for f in frames:
        strip.paste(f, (x, 0))
        x += f.width
    strip.save(args.out)
    print(f"wrote {args.out}: {args.modes} of {args.model}, {args.size} each")


if __name__ == "__main__":
    main()
