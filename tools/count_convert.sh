#!/usr/bin/env bash
# Instructions and mispredicted branches of `spt convert` on a 210,000-point cloud (the
# torus knot's vertices, `gen_model --segments 700 --sides 300 --no-faces`), on one
# thread under valgrind's cachegrind: counts that do not move with the machine's load,
# for changes too small for a wall clock to resolve (docs/load-and-convert.md).
#   tools/count_convert.sh SPT...       (one or more spt binaries, counted in turn)
# Prints, per binary, its instructions, branches, mispredicted branches
# and the md5 of the file it wrote (the same file for changes that keep the bytes).
# Needs valgrind (apt-get install -y valgrind); about a minute per binary.
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: tools/count_convert.sh SPT..." >&2; exit 2; }
# The binaries as given from the caller's directory.
spts=()
for spt in "$@"; do spts+=("$(realpath "$spt")"); done
cd "$(dirname "$0")/.."
command -v valgrind > /dev/null || { echo "count_convert.sh: valgrind is not installed" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cargo build --release --quiet --example gen_model
./target/release/examples/gen_model --segments 700 --sides 300 --no-faces \
  -o "$work/cloud.ply" > /dev/null
for spt in "${spts[@]}"; do
  RAYON_NUM_THREADS=1 valgrind --tool=cachegrind --cache-sim=no --branch-sim=yes \
    --cachegrind-out-file="$work/cg.out" "$spt" convert "$work/cloud.ply" "$work/cloud.spt" \
    > /dev/null 2> "$work/log"
  ir=$(awk '/I *refs:/ { print $NF }' "$work/log")
  branches=$(awk '/Branches:/ { print $3 }' "$work/log")
  missed=$(awk '/Mispredicts:/ { print $3 }' "$work/log")
  sum=$(md5sum "$work/cloud.spt" | cut -c1-8)
  printf '%s: %s instructions, %s branches, %s mispredicted, file %s\n' \
    "$spt" "$ir" "$branches" "$missed" "$sum"
done
