#!/usr/bin/env bash
# The CPU's plan of a frame (docs/viewer.md) against the threads it runs on: for each
# MODEL (an .spt file) and thread count (1, 2, 4 … up to the machine's cores), the
# median "cpu plan" of
#   spt render MODEL --size 1920x1080 --frames FRAMES --prefix-cut CUT [--gpu-memory BUDGET]
# with the prefixes cut at the node and at the block, alternated, and the nodes the GPU
# tested. Prints a Markdown table. Without BUDGET the whole model goes to the GPU where
# it fits. The models of the docs are made by
#   cargo run --release --example gen_model -- --preset lucy -o data/large/lucy_knot.ply
#   cargo run --release --example gen_cloud    # data/large/city_200m.las, 200 M points
#   spt convert data/large/X.{ply,las} data/large/X.spt --memory 4096
#
#   tools/bench_plan.sh data/large/lucy_knot.spt data/large/city_200m.spt
#   SPT=path/spt FRAMES=20 BUDGET=2048 tools/bench_plan.sh MODEL…
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 1 ] || { echo "usage: tools/bench_plan.sh MODEL.spt…" >&2; exit 2; }
frames=${FRAMES:-20}
if [ -z "${SPT:-}" ]; then
  cargo build --release --quiet --bin spt
  SPT=./target/release/spt
fi
budget=()
[ -n "${BUDGET:-}" ] && budget=(--gpu-memory "$BUDGET")
cores=$(nproc)
threads=()
for ((t = 1; t < cores; t *= 2)); do threads+=("$t"); done
threads+=("$cores")
shot=$(mktemp --suffix .png)
trap 'rm -f "$shot"' EXIT

echo "| model | threads | plan, cut at the node | plan, cut at the block | nodes tested, node / block | ε |"
echo "| --- | --- | --- | --- | --- | --- |"
for model in "$@"; do
  for t in "${threads[@]}"; do
    plan=(); tested=(); eps=""
    for cut in node block; do
      out=$(RAYON_NUM_THREADS=$t "$SPT" render "$model" --size 1920x1080 --frames "$frames" \
        --prefix-cut "$cut" "${budget[@]}" -o "$shot" 2>&1) || {
        echo "bench_plan.sh: spt render $model failed:" >&2; echo "$out" >&2; exit 1; }
      plan+=("$(echo "$out" | awk '/^cpu plan/ {print $3}')")
      tested+=("$(echo "$out" | sed -n 's/.*the GPU tested \([0-9,]*\) nodes.*/\1/p')")
      eps=$(echo "$out" | sed -n 's/.*ε = \([0-9.]*\) px.*/\1 px (coarsened)/p')
    done
    echo "| $(basename "$model") | $t | ${plan[0]} ms | ${plan[1]} ms | ${tested[0]} / ${tested[1]} | ${eps:-as asked} |"
  done
done
