#!/usr/bin/env bash
# Render benchmark: GPU time per frame (timestamp queries, median and p95)
# and splats/s at 1024×768, leaves only and at ε = 1 px, for bunny and the Lucy-size
# model, with both culling strategies, on whatever adapter `spt render` picks
# (SPT_BACKEND chooses). Prints a Markdown table.
#
#   tools/bench_render.sh               # FRAMES=9 (Lucy leaves only: LUCY_FRAMES=3)
set -euo pipefail
cd "$(dirname "$0")/.."
frames=${FRAMES:-9}
lucy_frames=${LUCY_FRAMES:-3}
data=${SPT_DATA:-../shared/data}
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo build --release --quiet --bin spt --example gen_model
mkdir -p data/large
[ -f data/large/lucy_knot.ply ] || ./target/release/examples/gen_model --preset lucy
[ -f data/large/lucy_knot.spt ] || ./target/release/spt convert data/large/lucy_knot.ply data/large/lucy_knot.spt > /dev/null
out=$(mktemp)
adapter=""
echo "| model | ε | splats drawn | nodes the GPU tested | culling | GPU ms (median, p95) | M splats/s |"
echo "| --- | --- | --- | --- | --- | --- | --- |"
for model in "$data/bunny.ply" data/large/lucy_knot.spt; do
  for lod in leaves 1; do
    n=$frames
    [ "$model" = data/large/lucy_knot.spt ] && [ $lod = leaves ] && n=$lucy_frames
    for culling in vertex compute; do
      flags=(--error-px 1)
      [ $lod = leaves ] && flags=(--no-lod)
      ./target/release/spt render "$model" -o "$out.png" --size 1024x768 --frames "$n" --culling $culling "${flags[@]}" > "$out" 2>/dev/null
      adapter=$(sed -n 's/^adapter *//p' "$out")
      drawn=$(sed -n 's/^splats *\([0-9,]*\) drawn.*/\1/p' "$out")
      tested=$(sed -n 's/.*the GPU tested \([0-9,]*\) nodes.*/\1/p' "$out")
      gpu=$(sed -n 's/^gpu time *\([0-9.]*\) ms (median of [0-9]*), p95 \([0-9.]*\) ms/\1, \2/p' "$out")
      rate=$(sed -n 's/^rate *\([0-9.]*\) M.*/\1/p' "$out")
      echo "| $(basename "$model") | $lod | $drawn | $tested | $culling | ${gpu:-n/a} | ${rate:-n/a} |"
    done
  done
done
echo
echo "Adapter: $adapter. $(date +%F), $(nproc) cores ($(sed -n 's/^model name\s*: //p' /proc/cpuinfo | head -1))."
rm -f "$out" "$out.png"
