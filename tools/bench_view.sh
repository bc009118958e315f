#!/usr/bin/env bash
# Viewer benchmark on the Lucy-size generated model, in a real window (an
# X display: $DISPLAY, else Xvfb started here):
#   - launch to first frame, as .spt (RUNS runs, median) and as PLY (converted in the
#     background; one run), read from spt view's own log;
#   - frame times while orbiting (--spin, FRAMES frames once the model is on the GPU);
#   - a screenshot of the window while the PLY converts, taken by the viewer's own
#     screenshot key (F12, sent with xdotool) -> docs/viewer_loading.png.
# Prints a Markdown table.
#
#   tools/bench_view.sh          # RUNS=5 FRAMES=20; needs xvfb and xdotool
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${RUNS:-5}
frames=${FRAMES:-20}
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo build --release --quiet --bin spt --example gen_model
mkdir -p data/large
[ -f data/large/lucy_knot.ply ] || ./target/release/examples/gen_model --preset lucy
[ -f data/large/lucy_knot.spt ] || ./target/release/spt convert data/large/lucy_knot.ply data/large/lucy_knot.spt > /dev/null
source tools/display.sh
log=$(mktemp)
shot=$(mktemp --suffix .png)
median() { sort -n | awk '{v[NR]=$1} END {print v[int((NR+1)/2)]}'; }

# .spt: launch to first frame, and to the whole model on the GPU.
first=(); whole=()
for _ in $(seq "$runs"); do
  ./target/release/spt view data/large/lucy_knot.spt --size 1024x768 --frames 1 --screenshot "$shot" > /dev/null 2> "$log"
  first+=("$(sed -n 's/^first frame \([0-9.]*\) s.*/\1/p' "$log")")
  whole+=("$(sed -n 's/.* on the GPU in \([0-9.]*\) s.*/\1/p' "$log")")
done
spt_first=$(printf '%s\n' "${first[@]}" | median)
spt_whole=$(printf '%s\n' "${whole[@]}" | median)
spt_stages=$(sed -n 's/.* on the GPU in [0-9.]* s (\(.*\))/\1/p' "$log")

# PLY: converted in the background; F12 during the conversion saves the window.
rm -f spt-screenshot-*.png
./target/release/spt view data/large/lucy_knot.ply --size 1024x768 --frames 1 --screenshot "$shot" > /dev/null 2> "$log" &
viewer=$!
sleep 4
window=$(xdotool search --sync --pid "$viewer" | head -1)
xdotool windowfocus --sync "$window" 2> /dev/null || true
xdotool key F12
wait $viewer
ply_first=$(sed -n 's/^first frame \([0-9.]*\) s.*/\1/p' "$log")
ply_stages=$(sed -n 's/.* on the GPU in [0-9.]* s (\(.*\))/\1/p' "$log")
loading_shot=$(ls spt-screenshot-*.png 2> /dev/null | head -1 || true)
[ -n "$loading_shot" ] && mv "$loading_shot" docs/viewer_loading.png

# Orbiting: 2° of azimuth per frame.
./target/release/spt view data/large/lucy_knot.spt --size 1024x768 --spin 2 --frames "$frames" --screenshot "$shot" > "$log" 2>&1
orbit_frame=$(sed -n 's/^frame *\(.*\)/\1/p' "$log")
orbit_gpu=$(sed -n 's/^gpu *\(.*\)/\1/p' "$log")
orbit_splats=$(sed -n 's/^splats *\(.*\)/\1/p' "$log")
adapter=$(sed -n 's/^adapter *//p' "$log")

echo "| lucy_knot (14,028,800 vertices), 1024×768 | result |"
echo "| --- | --- |"
echo "| .spt: launch to first frame (median of $runs) | $spt_first s |"
echo "| .spt: launch to the whole list on the GPU | $spt_whole s ($spt_stages) |"
echo "| PLY: launch to first frame (converted in the background) | $ply_first s ($ply_stages) |"
echo "| orbiting, 2° per frame, ε = 1 px: time between frames | $orbit_frame |"
echo "| orbiting: GPU time per frame | $orbit_gpu |"
echo "| orbiting: splats | $orbit_splats |"
echo
echo "Adapter: $adapter. $(date +%F), $(nproc) cores ($(sed -n 's/^model name\s*: //p' /proc/cpuinfo | head -1))."
[ -n "$loading_shot" ] && echo "Window during the PLY conversion: docs/viewer_loading.png"
rm -f "$log" "$shot"
