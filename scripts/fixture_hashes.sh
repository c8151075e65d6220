#!/usr/bin/env bash
# Prints a SHA-256 per output of a fixed set of meshflow runs on the shared real data and on
# meshflow's own synthetic scenes. Run before and after a change that must not alter
# behaviour (a restructuring) and diff the two listings: every line must match.
#   scripts/fixture_hashes.sh [BUILD_DIR] > before.txt
# Needs $MESHFLOW_DATA (default ../shared/data); runs on 2 threads; takes about a minute.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
mf="$build/meshflow"
data=${MESHFLOW_DATA:-../shared/data}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
run() { "$mf" "$@" --threads 2 -q >/dev/null; }

run reconstruct "$data/kurt3d/scan000.3d" -o "$out/kurt3d_default.ply" --voxel 0.05
run reconstruct "$data/kurt3d/scan000.3d" -o "$out/kurt3d_all.ply" --voxel 0.05 \
  --optimize clean,holes,planes,sharpen,retriangulate,remesh,decimate
run reconstruct "$data/kurt3d/scan000.3d" -o "$out/kurt3d_emc.ply" --voxel 0.05 --extract emc
run reconstruct "$data/kurt3d/scan000.3d" -o "$out/kurt3d_pmc.ply" --voxel 0.05 --extract pmc
run reconstruct "$data/kurt3d/scan000.3d" -o "$out/kurt3d_mt.ply" --voxel 0.05 --extract mt
run reconstruct "$data/objects/bunny.pcd" -o "$out/bunny.ply"
run reconstruct "$data/kinect_pcl/table_scene_mug_stereo_textured.pcd" -o "$out/mug.ply"
run reconstruct "$data/kinect_pcl/office1.pcd" -o "$out/office.obj" --texture
run optimize "$out/kurt3d_default.ply" "$out/kurt3d_optimized.ply" --optimize planes,retriangulate,decimate
run run "$data/kurt3d" -o "$out/kurt3d_merged" --merged --voxel 0.1
run run "$data/rgbd_redwood" -o "$out/redwood_rqt" --triangulate rqt --decimate 0.25 --max-frames 3
run run "$data/rgbd_redwood" -o "$out/redwood_fused" --fuse --max-frames 6 --save-map "$out/redwood.map"
run run --synthetic -o "$out/synthetic_scans" --max-frames 3
run run --synthetic-depth -o "$out/synthetic_depth" --triangulate naive --max-frames 3
run demo -o "$out/demo.ply"
"$mf" sample torus -o "$out/torus_points.ply" -q
run reconstruct "$out/torus_points.ply" -o "$out/torus.ply"

cd "$out"
find . -type f ! -name '*.json' | sort | xargs sha256sum
