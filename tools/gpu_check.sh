#!/usr/bin/env bash
# The figures of docs/gpu.md on a machine with a real GPU, in one run: `spt render`
# frame times by pass at 1920×1080 (the default model, the Lucy-size generated model,
# the LiDAR tile; splats shaded and as points), then the image-quality test on that
# adapter. Run from the repository root:
#
#   tools/gpu_check.sh                       # builds with cargo
#   SPT=path/spt GEN_MODEL=path/gen_model tools/gpu_check.sh   # prebuilt binaries
#
# Models from $SPT_DATA (default ../shared/data); the Lucy-size model is generated into
# data/large/ once (533 MB). FRAMES (default 20) frames per view. Prints one block per
# view: adapter, splats, GPU time (median, p95), passes, rate.
set -euo pipefail
cd "$(dirname "$0")/.."
data=${SPT_DATA:-../shared/data}
frames=${FRAMES:-20}
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
if [ -z "${SPT:-}" ]; then
  cargo build --release --quiet --bin spt --example gen_model
  SPT=./target/release/spt
  GEN_MODEL=./target/release/examples/gen_model
fi
lucy=data/large/lucy_knot.ply
if [ ! -f "$lucy" ]; then
  mkdir -p data/large
  "$GEN_MODEL" --preset lucy -o "$lucy" > /dev/null
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

views=(
  "data/torus_knot.ply|"
  "data/torus_knot.ply|--mode points"
  "$lucy|"
  "$lucy|--orbit 30,20,1.3"
  "$lucy|--orbit 30,20,1.3 --mode points"
  "$lucy|--error-px 0"
  "$lucy|--error-px 0 --mode points"
  "$data/terrain_utm.ply|"
  "$data/terrain_utm.ply|--orbit 30,35,1.0"
)
for view in "${views[@]}"; do
  model=${view%%|*}
  args=${view#*|}
  echo "== $(basename "$model") ${args:-(default view)}"
  # shellcheck disable=SC2086
  "$SPT" render "$model" -o "$out/frame.png" --size 1920x1080 --frames "$frames" $args |
    grep -E '^(adapter|splats|gpu time|passes|rate)' | sed 's/^/   /'
done

if command -v cargo > /dev/null && [ -z "${SKIP_TESTS:-}" ]; then
  echo "== image quality on this adapter (cargo test --release render_flip)"
  cargo test --release --quiet --test all -- render_flip:: --nocapture 2>&1 |
    grep -E '^adapter|FLIP|^test result' | sed 's/^/   /' || true
fi
