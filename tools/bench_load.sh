#!/usr/bin/env bash
# Load benchmark on the Lucy-size model (14,028,800 vertices / 28,057,600 triangles,
# 533 MB binary PLY): page-cache read speed of the file, then `spt info` (load MB/s,
# surfels/s, peak memory), median of RUNS runs, as a Markdown table for docs/load-and-convert.md.
#
#   tools/bench_load.sh            # RUNS=5
#   RUNS=9 tools/bench_load.sh
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${RUNS:-5}
file=data/large/lucy_knot.ply

cargo build --release --quiet --bin spt --example gen_model
[ -f "$file" ] || ./target/release/examples/gen_model --preset lucy
cat "$file" > /dev/null # into the page cache

# Page-cache read speed of the same file (best of 3).
cache=$(for _ in 1 2 3; do dd if="$file" of=/dev/null bs=16M 2>&1 | tail -1; done |
  python3 -c 'import sys,re
best=0
for l in sys.stdin:
    m=re.match(r"(\d+) bytes.* s, ",l); t=float(l.split(" s, ")[0].split(", ")[-1])
    best=max(best,int(m.group(1))/t/1e6)
print(f"{best:.0f}")')

results=$(mktemp)
for _ in $(seq "$runs"); do
  ./target/release/spt info --json "$file" >> "$results"
  echo >> "$results"
done
python3 - "$results" "$cache" "$runs" "$file" <<'PY'
import json, sys, statistics, platform, os, datetime
text = open(sys.argv[1]).read()
dec = json.JSONDecoder(); runs = []; i = 0
while i < len(text):
    if text[i].isspace(): i += 1; continue
    obj, i = dec.raw_decode(text, i); runs.append(obj)
cache, n, path = float(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
med = lambda f: statistics.median(f(r) for r in runs)
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), platform.machine())
mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
r0 = runs[0]
print(f"Load of `{path}` ({r0['bytes']/1e6:.0f} MB, {r0['surfels']['count']:,} vertices, "
      f"{r0['geometry']['triangles']:,} triangles), median of {n} runs of `spt info`; "
      f"{datetime.date.today()}, {os.cpu_count()} cores ({cpu}), {mem:.0f} GiB.\n")
print("| measure | value |")
print("| --- | --- |")
print(f"| page-cache read of the file (`dd`, best of 3) | {cache:,.0f} MB/s |")
print(f"| load (parse + rebase), median | {med(lambda r: r['timing']['load_seconds'])*1e3:.0f} ms = {med(lambda r: r['timing']['load_mb_per_s']):,.0f} MB/s |")
print(f"| load, slowest run | {max(r['timing']['load_seconds'] for r in runs)*1e3:.0f} ms |")
print(f"| leaf surfels, median | {med(lambda r: r['timing']['surfels_seconds'])*1e3:.0f} ms = {med(lambda r: r['timing']['surfels_per_second'])/1e6:.1f} M surfels/s |")
print(f"| peak resident memory (includes the 533 MB file mapping) | {med(lambda r: r['peak_memory_bytes'])/2**30:.2f} GiB |")
PY
rm -f "$results"
