#!/usr/bin/env bash
# Checks that two builds of spt give byte-identical outputs: `spt render` of the default
# model, bunny and the LAZ tile in every display mode, and `spt convert` of every shared mesh and
# cloud. For refactors that must not change behaviour. The renders cull in the vertex
# stage (`--culling vertex`): compute culling appends survivors with atomics, so their
# order, and the last bits of the blended sums, change from one run to the next.
#
#   tools/same_outputs.sh OLD_SPT NEW_SPT [OUT_DIR]
#
# OLD_SPT and NEW_SPT are spt binaries (e.g. a build of an older commit in a worktree).
# Models come from $SPT_DATA (default ../shared/data). Prints one line per output and
# exits 1 if any differ.
set -euo pipefail
old=${1:?usage: tools/same_outputs.sh OLD_SPT NEW_SPT [OUT_DIR]}
new=${2:?usage: tools/same_outputs.sh OLD_SPT NEW_SPT [OUT_DIR]}
cd "$(dirname "$0")/.."
data=${SPT_DATA:-../shared/data}
out=${3:-$(mktemp -d)}
mkdir -p "$out/old" "$out/new"
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}

modes="shaded levels normals radius points mesh edl elevation classification intensity returns"
differ=0
same() { # NAME: compares old/NAME with new/NAME
  if cmp -s "$out/old/$1" "$out/new/$1"; then
    echo "same    $1"
  else
    echo "DIFFERS $1"
    differ=1
  fi
}
for model in data/torus_knot.ply "$data/bunny.ply" "$data/autzen_trim.laz"; do
  name=$(basename "${model%.*}")
  runs=()
  for mode in $modes; do
    # A cloud has no mesh to draw.
    [ "$mode" = mesh ] && [[ "$model" == *.la[sz] ]] && continue
    runs+=("$mode:--mode $mode")
  done
  runs+=("leaves:--error-px 0" "no_ewa:--no-ewa" "back_faces:--cull-back-faces")
  for run in "${runs[@]}"; do
    tag=${run%%:*}
    args=${run#*:}
    for side in old new; do
      bin=$old
      [ "$side" = new ] && bin=$new
      # shellcheck disable=SC2086
      "$bin" render "$model" -o "$out/$side/${name}_$tag.png" --size 512x384 \
        --culling vertex $args > /dev/null
    done
    same "${name}_$tag.png"
  done
done
for model in "$data"/*.ply "$data"/*.las "$data"/*.laz; do
  name=$(basename "$model")
  for side in old new; do
    bin=$old
    [ "$side" = new ] && bin=$new
    "$bin" convert "$model" "$out/$side/$name.spt" > /dev/null
  done
  same "$name.spt"
done
exit $differ
