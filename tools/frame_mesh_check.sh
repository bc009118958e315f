#!/usr/bin/env bash
# The shared kinect frame meshed on its sensor grid (src/io/triangulate.rs, every
# triangle wound to face the sensor) against the same frame as a cloud, from its sensor
# and from three eyes 0.4 m beside it, leaves only, 640×480: per view, FLIP of the
# mesh's splats against the cloud's splats, and of the cloud's splats against the mesh
# itself drawn by the mesh pass (--mode mesh). With OLD=path/to/spt, also the mesh's
# splats drawn by that binary against the cloud's.
#
#   tools/frame_mesh_check.sh [OUT_DIR]      (SPT_DATA: the shared data folder)
set -euo pipefail
cd "$(dirname "$0")/.."
data="${SPT_DATA:-../shared/data}"
out="${1:-target/frame_mesh_check}"
mkdir -p "$out"
cargo build --release --quiet --bin spt --example cloud_quality --example image_flip
spt=target/release/spt
flip=target/release/examples/image_flip
target/release/examples/cloud_quality "$data/kinect_rgb.ply" --grid 640x480 \
  --write-mesh "$out/kinect_grid.ply"
# The frame's box centre; the sensor at the file's origin looks down +z, image up −y.
look=(--target 0.37,-0.59,2.33 --up=-y --size 640x480 --no-lod)
k=0
for eye in 0,0,0 0.4,0,0 -0.4,0,0 0,-0.4,0; do
  "$spt" render "$data/kinect_rgb.ply" --eye "$eye" "${look[@]}" -o "$out/cloud_$k.png" > /dev/null
  "$spt" render "$out/kinect_grid.ply" --eye "$eye" "${look[@]}" -o "$out/mesh_splats_$k.png" > /dev/null
  "$spt" render "$out/kinect_grid.ply" --eye "$eye" "${look[@]}" --mode mesh \
    -o "$out/mesh_$k.png" > /dev/null
  echo "view $k (eye $eye):"
  echo "  the mesh's splats against the cloud's:   $("$flip" "$out/mesh_splats_$k.png" "$out/cloud_$k.png")"
  echo "  the cloud's splats against the mesh:     $("$flip" "$out/cloud_$k.png" "$out/mesh_$k.png")"
  if [ -n "${OLD:-}" ]; then
    "$OLD" render "$out/kinect_grid.ply" --eye "$eye" "${look[@]}" -o "$out/old_mesh_splats_$k.png" > /dev/null
    echo "  OLD's mesh splats against the cloud's:   $("$flip" "$out/old_mesh_splats_$k.png" "$out/cloud_$k.png")"
  fi
  k=$((k + 1))
done
