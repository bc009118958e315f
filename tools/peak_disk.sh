#!/usr/bin/env bash
# The most disk a command takes in a folder while it runs: the blocks held under DIR
# (`du --block-size=1`: a sparse or partly freed file counts what it holds, not its
# length), sampled every 0.2 s, less what DIR held before. Prints the command's own
# output, then "peak BYTES" and the command's wall time.
#
#   tools/peak_disk.sh DIR COMMAND [ARGS…]
#   tools/peak_disk.sh /data/out spt convert scan.laz /data/out/scan.spt --out-of-core
set -euo pipefail
if [ $# -lt 2 ]; then
    sed -n '2,7p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
fi
dir=$1
shift
held() { du -s --block-size=1 "$dir" | cut -f1; }
base=$(held)
peak=$base
start=$(date +%s.%N)
"$@" &
pid=$!
while kill -0 "$pid" 2>/dev/null; do
    now=$(held 2>/dev/null || echo "$base")
    [ "$now" -gt "$peak" ] && peak=$now
    sleep 0.2
done
wait "$pid"
end=$(date +%s.%N)
printf "peak %d bytes over %s's %d; %.1f s\n" $((peak - base)) "$dir" "$base" "$(echo "$end - $start" | bc)"
