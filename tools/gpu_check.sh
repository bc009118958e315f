#!/usr/bin/env bash
# The figures of docs/gpu.md in one run: `spt render` frame times by pass for both ways
# of drawing the splats (`--raster hardware`, the GPU's raster pipeline, and `--raster
# compute`, compute rasterization), alternated view by view, printed as one Markdown
# table: per model, view and mode, the splats drawn, GPU ms in all and per pass
# (visibility / attributes / shading; the cull pass counts in visibility, the compute
# path's resolve in shading), splats per second, and the CPU's plan of a frame. Run from
# the repository root:
#
#   tools/gpu_check.sh                 # 1920×1080, 20 frames: the default model, the
#                                      # Lucy-size generated model (made and converted
#                                      # into data/large/ once), the LiDAR tile, and the
#                                      # forest scene (10⁵ trees of 10⁶ samples on the
#                                      # tile, tools/gen_forest.rs, made once), its far
#                                      # instances placed by the GPU and, for
#                                      # comparison, all planned on the CPU
#   tools/gpu_check.sh --quick         # 320×240, 3 frames, the default model and the
#                                      # tile: a check that both paths run (CI)
#   SPT=path/spt GEN_MODEL=path/gen_model GEN_FOREST=path/gen_forest SPT_DATA=path \
#     tools/gpu_check.sh
#                                      # prebuilt binaries: no cargo needed
#
# Without SPT it builds the binaries with cargo. FRAMES and SIZE override the frame
# count and size. Fails when a render fails, or when the two paths draw different
# numbers of splats.
set -euo pipefail
cd "$(dirname "$0")/.."
quick=0
for arg in "$@"; do
  case $arg in
    --quick) quick=1 ;;
    -h | --help) sed -n '2,25p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "gpu_check.sh: unknown option $arg (use --quick or --help)" >&2; exit 2 ;;
  esac
done
data=${SPT_DATA:-../shared/data}
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
if [ -z "${SPT:-}" ]; then
  cargo build --release --quiet --bin spt --example gen_model --example gen_forest
  SPT=./target/release/spt
  GEN_MODEL=./target/release/examples/gen_model
  GEN_FOREST=./target/release/examples/gen_forest
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

if [ "$quick" = 1 ]; then
  size=${SIZE:-320x240}
  frames=${FRAMES:-3}
  views=(
    "data/torus_knot.ply|"
    "data/torus_knot.ply|--mode points"
    "data/torus_knot.ply|--error-px 0"
    "$data/terrain_utm.ply|"
  )
else
  size=${SIZE:-1920x1080}
  frames=${FRAMES:-20}
  lucy=data/large/lucy_knot.spt
  if [ ! -f "$lucy" ]; then
    mkdir -p data/large
    [ -f data/large/lucy_knot.ply ] || "$GEN_MODEL" --preset lucy -o data/large/lucy_knot.ply > /dev/null
    "$SPT" convert data/large/lucy_knot.ply "$lucy" > /dev/null
  fi
  forest=data/large/forest/forest.json
  if [ ! -f "$forest" ] && [ -f "$data/terrain_utm.ply" ]; then
    "$GEN_FOREST" --out data/large/forest --terrain "$data/terrain_utm.ply" > /dev/null
  fi
  views=(
    "data/torus_knot.ply|"
    "data/torus_knot.ply|--mode points"
    "$forest|"
    "$forest|--cpu-instances"
    "$forest|--eye 512300,5403300,380 --target 512700,5403700,300"
    "$forest|--eye 512300,5403300,380 --target 512700,5403700,300 --cpu-instances"
    "$lucy|"
    "$lucy|--orbit 30,20,1.3"
    "$lucy|--orbit 30,20,1.3 --mode points"
    "$lucy|--error-px 0"
    "$lucy|--error-px 0 --mode points"
    "$data/terrain_utm.ply|"
    "$data/terrain_utm.ply|--orbit 30,35,1.0"
  )
fi

# One render's row: splats (the GPU's count), GPU ms, passes, rate, CPU plan.
row() {
  awk '
    /^adapter/   { sub(/^adapter +/, ""); adapter = $0 }
    /^culled/    { drawn = $2 }
    /^gpu time/  { gpu = $3 }
    /^passes/    { pass = $3 " / " $6 " / " $9 }
    /^rate/      { rate = $2 " M" }
    /^cpu plan/  { plan = $3 }
    END { printf "%s|%s|%s|%s|%s|%s\n", adapter, drawn, gpu, pass, rate, plan }' "$1"
}

failed=0
adapter=""
table="| model and view | raster | splats | GPU ms | visibility / attributes / shading | splats/s | CPU plan ms |
| --- | --- | --- | --- | --- | --- | --- |"
for view in "${views[@]}"; do
  model=${view%%|*}
  args=${view#*|}
  if [ ! -f "$model" ]; then
    echo "skip      $model (not found; set SPT_DATA)" >&2
    continue
  fi
  name="$(basename "$model") ${args:-(default view)}"
  drawn=()
  for raster in hardware compute; do
    log="$out/$raster.log"
    # shellcheck disable=SC2086
    if ! "$SPT" render "$model" -o "$out/frame.png" --size "$size" --frames "$frames" \
      --raster "$raster" $args > "$log" 2>&1; then
      echo "FAIL      $name, $raster raster:" >&2
      sed 's/^/          /' "$log" >&2
      failed=1
      continue
    fi
    IFS='|' read -r adapter count gpu passes rate plan < <(row "$log")
    drawn+=("$count")
    table+="
| $name | $raster | $count | $gpu | $passes | $rate | $plan |"
    echo "ok        $name, $raster: $gpu ms GPU" >&2
  done
  if [ "${#drawn[@]}" = 2 ] && [ "${drawn[0]}" != "${drawn[1]}" ]; then
    echo "FAIL      $name: $size, the paths drew ${drawn[0]} and ${drawn[1]} splats" >&2
    failed=1
  fi
done
echo
echo "Adapter: $adapter; $size, median of $frames frames, $(date -u +%F)."
echo
echo "$table"
exit $failed
