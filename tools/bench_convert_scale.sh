#!/usr/bin/env bash
# Conversion at scale, against PotreeConverter 2 built from its public
# source (tools/build_potree.sh): the Lucy-size mesh (14,028,800 vertices; spt reads the
# PLY, Potree the same points as LAS, both written by gen_model), the same vertices as a cloud
# (`gen_model --preset lucy --no-faces`, in memory) and a generated city tile of
# 200 M points with colours (LAS, tools/gen_cloud.rs). Lucy is converted in memory (the
# default where it fits) and out of core (--out-of-core --memory LUCY_MEMORY_MIB, 1024
# by default). Runs alternate spt and Potree on one machine; wall time and peak resident
# memory from GNU time. Where Open3D is installed (pip install open3d), its normal
# estimation alone on the Lucy-size cloud (tools/open3d_normals.py, k = 24) runs in the
# same rotation: the neighbour search and fit that any splat needs, without the rest of
# a conversion; so, where SciPy is installed (pip install scipy), does its k-d tree's
# search for the same 24 nearest (tools/kdtree_neighbours.py). Prints a Markdown table.
#
#   tools/bench_convert_scale.sh          # RUNS=3 on Lucy, 1 on the 200 M tile
#   POINTS=50000000 tools/bench_convert_scale.sh   # a smaller tile
#   CITY=0 tools/bench_convert_scale.sh   # Lucy only
#   MESH=0 CITY=0 tools/bench_convert_scale.sh   # the Lucy-size cloud only
#   TUNABLES="glibc.malloc.mmap_max=0 glibc.malloc.hugetlb=1" tools/bench_convert_scale.sh
#                                         # the cloud also with each of these glibc
#                                         # allocator settings, in the same rotation
#   SPT=… GEN_MODEL=… GEN_CLOUD=… POTREE=… tools/bench_convert_scale.sh
#                                         # prebuilt binaries: no cargo or cmake needed
#                                         # (a machine without a toolchain; python3 for
#                                         # the table)
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${RUNS:-3}
points=${POINTS:-200000000}
memory=${MEMORY_MIB:-4096}
lucy_memory=${LUCY_MEMORY_MIB:-1024}
city_wanted=${CITY:-1}
mesh_wanted=${MESH:-1}
if [ -z "${SPT:-}" ]; then
  cargo build --release --quiet --bin spt --example gen_model --example gen_cloud
  SPT=./target/release/spt
  GEN_MODEL=./target/release/examples/gen_model
  GEN_CLOUD=./target/release/examples/gen_cloud
fi
potree=${POTREE:-$(tools/build_potree.sh)}
mkdir -p data/large
lucy=data/large/lucy_knot.ply
cloud=data/large/lucy_cloud.ply
city=data/large/city_$((points / 1000000))m.las
# Each PLY and the same points as LAS, made together where either is missing.
made() { [ -f "$1" ] && [ -f "${1%.ply}.las" ]; }
if [ "$mesh_wanted" != 0 ] && ! made "$lucy"; then
  "$GEN_MODEL" --preset lucy -o "$lucy" --las "${lucy%.ply}.las" > /dev/null
fi
made "$cloud" || "$GEN_MODEL" --preset lucy --no-faces -o "$cloud" --las "${cloud%.ply}.las" > /dev/null
[ "$city_wanted" = 0 ] || [ -f "$city" ] || "$GEN_CLOUD" --points "$points" --out "$city"
logs=$(mktemp -d)
open3d=0
python3 -c "import open3d" 2> /dev/null && open3d=1
scipy=0
python3 -c "import scipy.spatial" 2> /dev/null && scipy=1
# One timed run: "seconds peak_kib" appended to $logs/$1, from GNU time where
# installed, else from Python's rusage.
timed() {
  local name=$1; shift
  if [ -x /usr/bin/time ]; then
    /usr/bin/time -f "%e %M" -o "$logs/time" "$@" > "$logs/$name.out" 2>&1
  else
    python3 -c '
import resource, subprocess, sys, time
start = time.monotonic()
subprocess.run(sys.argv[2:], stdout=open(sys.argv[1], "w"), stderr=subprocess.STDOUT, check=True)
peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
print(f"{time.monotonic() - start:.2f} {peak}")' "$logs/$name.out" "$@" > "$logs/time"
  fi
  cat "$logs/time" >> "$logs/$name"
}
for i in $(seq "$runs"); do
  if [ "$mesh_wanted" != 0 ]; then
    timed spt_lucy "$SPT" convert "$lucy" "$logs/lucy.spt"
    timed spt_lucy_ooc "$SPT" convert "$lucy" "$logs/lucy.spt" --out-of-core --memory "$lucy_memory"
    rm -rf "$logs/potree_out"
    timed potree_lucy "$potree" "${lucy%.ply}.las" -o "$logs/potree_out"
  fi
  timed spt_cloud "$SPT" convert "$cloud" "$logs/lucy.spt"
  k=0
  for tunables in ${TUNABLES:-}; do
    timed "spt_cloud_tunables_$k" env GLIBC_TUNABLES="$tunables" "$SPT" convert "$cloud" "$logs/lucy.spt"
    k=$((k + 1))
  done
  rm -rf "$logs/potree_out"
  timed potree_cloud "$potree" "${cloud%.ply}.las" -o "$logs/potree_out"
  if [ "$open3d" = 1 ]; then
    timed open3d_cloud python3 tools/open3d_normals.py "$cloud" 24
    cat "$logs/open3d_cloud.out" >> "$logs/open3d_cloud.fits"
  fi
  if [ "$scipy" = 1 ]; then
    timed kdtree_cloud python3 tools/kdtree_neighbours.py "$cloud" 24
    cat "$logs/kdtree_cloud.out" >> "$logs/kdtree_cloud.fits"
  fi
done
cp "$logs/spt_cloud.out" "$logs/spt_cloud.stages"
[ "$mesh_wanted" = 0 ] || cp "$logs/spt_lucy_ooc.out" "$logs/spt_lucy_ooc.stages"
if [ "$city_wanted" != 0 ]; then
timed spt_city "$SPT" convert "$city" "$logs/city.spt" --memory "$memory"
cp "$logs/spt_city.out" "$logs/spt_city.stages"
rm -f "$logs/city.spt"
if [ -z "${SKIP_POTREE_CITY:-}" ]; then
  rm -rf "$logs/potree_out"
  timed potree_city "$potree" "$city" -o "$logs/potree_out"
fi
fi
rm -rf "$logs/potree_out" "$logs/lucy.spt"
python3 - "$logs" "$points" "$lucy_memory" ${TUNABLES:-} <<'PY'
import sys, os, statistics, datetime
logs, points, lucy_memory = sys.argv[1], int(sys.argv[2]), sys.argv[3]
tunables = sys.argv[4:]
def runs(name):
    path = os.path.join(logs, name)
    if not os.path.exists(path):
        return None
    rows = [tuple(map(float, l.split())) for l in open(path) if l.strip()]
    return statistics.median(r[0] for r in rows), max(r[1] for r in rows) / 2**20, len(rows)
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
print(f"{datetime.date.today()}, {os.cpu_count()} cores ({cpu}), {mem:.0f} GiB; median wall time, largest peak memory.\n")
print("| model | points | spt convert | PotreeConverter 2 | time spt / Potree | memory spt / Potree |")
print("| --- | --- | --- | --- | --- | --- |")
rows = [("Lucy-size mesh, in memory", 14028800, "spt_lucy", "potree_lucy"), (f"Lucy-size mesh, out of core (--memory {lucy_memory})", 14028800, "spt_lucy_ooc", "potree_lucy"), ("Lucy-size cloud, in memory", 14028800, "spt_cloud", "potree_cloud")]
rows += [(f"Lucy-size cloud, in memory, GLIBC_TUNABLES={t}", 14028800, f"spt_cloud_tunables_{k}", "potree_cloud") for k, t in enumerate(tunables)]
rows.append((f"city tile", points, "spt_city", "potree_city"))
for label, n, a, b in rows:
    s, p = runs(a), runs(b)
    if s is None:
        continue
    cell = lambda r: "–" if r is None else f"{r[0]:.1f} s, {r[1]:.2f} GiB ({n / r[0] / 1e6:.2f} M points/s, {r[2]} run{'s' if r[2] > 1 else ''})"
    ratio = lambda k: "–" if p is None else f"{s[k] / p[k]:.2f}"
    print(f"| {label} | {n:,} | {cell(s)} | {cell(p)} | {ratio(0)} | {ratio(1)} |")
potree = runs("potree_cloud")
for name, what in [("open3d_cloud", "Open3D's normals alone on the Lucy-size cloud (read and fit"), ("kdtree_cloud", "SciPy's k-d tree alone on the Lucy-size cloud (read, build and search for the 24 nearest")]:
    peer = runs(name)
    if peer is None:
        continue
    fits = [l.strip() for l in open(os.path.join(logs, name + ".fits")) if l.strip()]
    print(f"\n{what}, median of {peer[2]}): {peer[0]:.1f} s, {peer[1]:.2f} GiB,")
    print(f"{peer[0] / potree[0]:.2f}× PotreeConverter's whole conversion of the same points. Its runs: " + "; ".join(fits) + ".")
for name, what in [("spt_lucy_ooc", "the Lucy-size mesh out of core (last run)"), ("spt_cloud", "the Lucy-size cloud (last run)"), ("spt_city", "the city tile")]:
    path = os.path.join(logs, name + ".stages")
    if os.path.exists(path):
        print(f"\nspt's stages on {what}:\n\n```")
        print(open(path).read().strip())
        print("```")
PY
