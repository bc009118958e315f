#!/usr/bin/env bash
# Convert benchmark: `spt convert` on a happy-Buddha-size model (543,232 vertices, the
# 2006 report's reference) and on the Lucy-size model (14,028,800 vertices / 28,057,600
# triangles), median of RUNS runs per stage, as a Markdown table for docs/load-and-convert.md.
#
#   tools/bench_convert.sh           # RUNS=3
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${RUNS:-3}
cargo build --release --quiet --bin spt --example gen_model
mkdir -p data/large
buddha=data/large/buddha_knot.ply
lucy=data/large/lucy_knot.ply
[ -f "$buddha" ] || ./target/release/examples/gen_model --segments 1061 --sides 512 --no-colors -o "$buddha"
[ -f "$lucy" ] || ./target/release/examples/gen_model --preset lucy

logs=$(mktemp -d)
for model in "$buddha" "$lucy"; do
  cat "$model" > /dev/null
  for i in $(seq "$runs"); do
    ./target/release/spt convert "$model" "${model%.ply}.spt" > "$logs/$(basename "$model" .ply).$i.log"
  done
done
python3 - "$logs" "$runs" <<'PY'
import sys, re, statistics, os, datetime, glob
logs, runs = sys.argv[1], int(sys.argv[2])
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
print(f"`spt convert`, median of {runs} runs; {datetime.date.today()}, {os.cpu_count()} cores ({cpu}), {mem:.0f} GiB.\n")
stages = ["load", "surfels", "tree", "errors", "sort", "write"]
rows = {}
for name in ["buddha_knot", "lucy_knot"]:
    per = {s: [] for s in stages}; total = []; peak = []; pts = []
    for f in sorted(glob.glob(f"{logs}/{name}.*.log")):
        text = open(f).read()
        for s in stages:
            per[s].append(float(re.search(rf"^\s*{s}\s+([\d.]+) s", text, re.M).group(1)))
        m = re.search(r"total ([\d.]+) s, ([\d.]+) M points/s(?:, peak memory ([\d.]+) GiB)?", text)
        total.append(float(m.group(1))); pts.append(float(m.group(2)))
        if m.group(3): peak.append(float(m.group(3)))
        nodes = re.search(r"^([\d,]+) nodes \(([\d,]+) leaves", text, re.M)
    rows[name] = (per, total, pts, peak, nodes.group(1), nodes.group(2))
print("| stage | Buddha size (s) | Lucy size (s) |")
print("| --- | --- | --- |")
for s in stages:
    print(f"| {s} | {statistics.median(rows['buddha_knot'][0][s]):.2f} | {statistics.median(rows['lucy_knot'][0][s]):.2f} |")
b, l = rows["buddha_knot"], rows["lucy_knot"]
print(f"| **total** | **{statistics.median(b[1]):.2f}** | **{statistics.median(l[1]):.2f}** |")
print(f"| points/s | {statistics.median(b[2]):.2f} M | {statistics.median(l[2]):.2f} M |")
if b[3] and l[3]:
    print(f"| peak memory | {statistics.median(b[3]):.2f} GiB | {statistics.median(l[3]):.2f} GiB |")
print(f"| leaves / nodes | {b[5]} / {b[4]} | {l[5]} / {l[4]} |")
PY
rm -rf "$logs"
