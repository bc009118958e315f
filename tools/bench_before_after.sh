#!/usr/bin/env bash
# GPU ms of `spt bench --quick` for an older commit and this checkout, alternated RUNS
# times on one machine (the cost tables of docs/image-quality.md and docs/gpu.md):
#   tools/bench_before_after.sh COMMIT [MODEL]      (RUNS=3 by default)
#   OLD_SPT=path SPT=path tools/bench_before_after.sh COMMIT [MODEL]
#                       (prebuilt binaries of COMMIT and of this checkout: no cargo needed)
# Builds COMMIT in a worktree under $TMPDIR; writes $OUT/{old,new}_N/results.csv and
# prints, per path and culling, the leaves-only GPU ms medians of each run.
set -euo pipefail
cd "$(dirname "$0")/.."
commit=${1:?usage: tools/bench_before_after.sh COMMIT [MODEL]}
model=${2:-data/torus_knot.ply}
runs=${RUNS:-3}
out=${OUT:-$(mktemp -d)}
if [ -z "${OLD_SPT:-}" ] || [ -z "${SPT:-}" ]; then
  old=${TMPDIR:-/tmp}/spt-before-$commit
  [ -d "$old" ] || git worktree add --detach "$old" "$commit" > /dev/null
  CARGO_TARGET_DIR="$old/target" cargo build --release --quiet --bin spt --manifest-path "$old/Cargo.toml"
  cargo build --release --quiet --bin spt
  OLD_SPT=$old/target/release/spt
  SPT=./target/release/spt
fi
for i in $(seq "$runs"); do
  "$OLD_SPT" bench "$model" --out "$out/old_$i" --quick --frames 5 > /dev/null
  "$SPT" bench "$model" --out "$out/new_$i" --quick --frames 5 > /dev/null
done
for f in "$out"/*_*/results.csv; do
  awk -F, -v run="$(basename "$(dirname "$f")")" \
    'NR > 1 && $5 == 0 { printf "%-6s %-12s %-8s %s ms\n", run, $2, $4, $9 }' "$f"
done | sort -k2,3 -k1
echo "results in $out"
