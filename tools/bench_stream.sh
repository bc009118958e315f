#!/usr/bin/env bash
# Streamed viewing under a GPU memory budget, in a real window (an X
# display: $DISPLAY, else Xvfb started here). For each MODEL (an .spt file), RUNS runs
# of
#   spt view MODEL --screenshot … --frames FRAMES --size 1024x768 --hide-panel
#                  --spin 2 --gpu-memory BUDGET
# and their medians, read from the viewer's own log: launch to first frame, the time
# between frames while orbiting, the GPU time, and the peak resident MiB. With COLD=1
# (as root) the page cache is dropped before each run, so the file is read from disk
# as on its first opening. Prints a Markdown table.
#
#   tools/bench_stream.sh data/large/city_200m.spt data/large/lucy_knot.spt
#   BUDGET=256 RUNS=3 FRAMES=20 COLD=1 tools/bench_stream.sh MODEL…
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 1 ] || { echo "usage: tools/bench_stream.sh MODEL.spt…" >&2; exit 2; }
runs=${RUNS:-3}
frames=${FRAMES:-20}
budget=${BUDGET:-1024}
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo build --release --quiet --bin spt
source tools/display.sh
log=$(mktemp)
shot=$(mktemp --suffix .png)
median() { sort -n | awk '{v[NR]=$1} END {print v[int((NR+1)/2)]}'; }
field() { sed -n "$1" "$log" | head -1; }

echo "| model | budget | first frame after launch | frame time, median | GPU time, median | resident (peak) | splats drawn |"
echo "| --- | --- | --- | --- | --- | --- | --- |"
for model in "$@"; do
  first=(); frame=(); gpu=(); peak=(); splats=()
  for _ in $(seq "$runs"); do
    if [ "${COLD:-0}" = 1 ]; then sync; echo 1 > /proc/sys/vm/drop_caches; fi
    ./target/release/spt view "$model" --screenshot "$shot" --frames "$frames" \
      --size 1024x768 --hide-panel --spin 2 --gpu-memory "$budget" > "$log" 2>&1
    first+=("$(field 's/^first frame \([0-9.]*\) s.*/\1/p')")
    frame+=("$(field 's/^frame *\([0-9.]*\) ms.*/\1/p')")
    gpu+=("$(field 's/^gpu *\([0-9.]*\) ms.*/\1/p')")
    peak+=("$(field 's/^gpu memory.*peak \([0-9.]*\) MiB.*/\1/p')")
    splats+=("$(field 's/^splats *\([0-9,]*\) drawn.*/\1/p' | tr -d ,)")
  done
  m() { printf '%s\n' "$@" | median; }
  echo "| $(basename "$model") | $budget MiB | $(m "${first[@]}") s | $(m "${frame[@]}") ms | $(m "${gpu[@]}") ms | $(m "${peak[@]}") MiB | $(m "${splats[@]}") |"
done
