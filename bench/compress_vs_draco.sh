#!/usr/bin/env bash
# Sizes of meshflow's compressed meshes beside Draco's (Debian's draco tools, 1.5.5) on meshes as
# meshflow writes them: the demo room and kurt3d scan000 at 5 cm (normals), a coloured Kinect
# cloud reconstructed and the fused Redwood map (normals and colours), made here from
# $MESHFLOW_DATA (the room alone without it). Positions at 14 bits on both sides; normals at
# equal error: Draco at its default (-qn 10), meshflow at the largest --normal-error (degrees)
# whose mean and 99th percentile angle (measured after decoding both, bench/mesh_error.py) are
# both no larger than Draco's; colours exact on both. Then positions only (the same positions:
# meshflow's decode).
# Prints markdown table rows. Speed: bench/nodes/bench_compress.cpp (in-process).
#   bench/compress_vs_draco.sh [BUILD_DIR]     (needs the `draco` package: draco_encoder)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
tool="$build/meshflow"
data=${MESHFLOW_DATA:-../shared/data}
py=/usr/bin/python3
err="$py bench/mesh_error.py"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
command -v draco_encoder > /dev/null || { echo "needs draco_encoder (apt-get install draco)" >&2; exit 2; }

"$tool" demo -o "$work/room.ply" -q
meshes=(room)
if [ -f "$data/kurt3d/scan000.3d" ]; then
  "$tool" reconstruct "$data/kurt3d/scan000.3d" --voxel 0.05 -o "$work/kurt3d.ply" -q
  meshes+=(kurt3d)
fi
kinect="$data/kinect_pcl/table_scene_mug_stereo_textured.pcd"
if [ -f "$kinect" ]; then
  "$tool" reconstruct "$kinect" -o "$work/kinect.ply" -q
  meshes+=(kinect)
fi
if [ -d "$data/rgbd_redwood" ]; then
  "$tool" run "$data/rgbd_redwood" --fuse --voxel 0.01 -o "$work/redwood" -q
  mv "$work/redwood/fused.ply" "$work/redwood.ply"
  meshes+=(redwood)
fi

json() { $py -c "import json,sys; print(json.load(sys.stdin)$1)"; }
size() { stat -c %s "$1"; }
echo "As written (normals; colours on kinect and redwood), equal error:"
echo
echo "| mesh | triangles | meshflow bytes (--normal-error) | Draco -cl 7 | Draco -cl 10 | meshflow / Draco 10 | normal angle mean / p99, meshflow / Draco (deg) | position error max, mm |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|"
for m in "${meshes[@]}"; do
  in="$work/$m.ply"
  draco_encoder -i "$in" -o "$work/$m.7.drc" -qp 14 -cl 7 > /dev/null
  draco_encoder -i "$in" -o "$work/$m.10.drc" -qp 14 -cl 10 > /dev/null
  draco_decoder -i "$work/$m.10.drc" -o "$work/$m.d.ply" > /dev/null
  de=$($err "$in" "$work/$m.d.ply")
  dp99=$(json "['normal_p99_deg']" <<<"$de")
  dmean=$(json "['normal_mean_deg']" <<<"$de")
  # The largest stated normal error at Draco's mean and p99 angle or better.
  for ne in 1.5 1.2 1.0 0.9 0.8 0.7 0.6 0.5 0.45 0.4 0.35 0.3 0.25 0.2 0.15 0.1; do
    "$tool" compress "$in" "$work/$m.mfc" --bits 14 --normal-error "$ne" -q
    "$tool" decompress "$work/$m.mfc" "$work/$m.m.ply" -q
    me=$($err "$in" "$work/$m.m.ply")
    ok=$($py -c "import sys; a = [float(x) for x in sys.argv[1:]]; print(int(a[0] <= a[1] and a[2] <= a[3]))" \
      "$(json "['normal_p99_deg']" <<<"$me")" "$dp99" "$(json "['normal_mean_deg']" <<<"$me")" "$dmean")
    [ "$ok" = 1 ] && break
  done
  tri=$("$tool" compress "$in" "$work/$m.mfc" --bits 14 --normal-error "$ne" --json | json "['triangles']")
  $py - "$m" "$tri" "$(size "$work/$m.mfc")" "$ne" "$(size "$work/$m.7.drc")" \
    "$(size "$work/$m.10.drc")" "$me" "$de" <<'PY'
import json, sys
m, tri, b, ne, d7, d10 = sys.argv[1:7]
me, de = json.loads(sys.argv[7]), json.loads(sys.argv[8])
tri, b, d7, d10 = int(tri), int(b), int(d7), int(d10)
print(f"| {m} | {tri:,} | {b:,} ({ne}°) | {d7:,} | {d10:,} | {b / d10:.3f} | "
      f"{me['normal_mean_deg']:.2f} / {me['normal_p99_deg']:.2f}, "
      f"{de['normal_mean_deg']:.2f} / {de['normal_p99_deg']:.2f} | "
      f"{me['max_position_error_mm']:.2f} / {de['max_position_error_mm']:.2f} |")
PY
done
echo
echo "Positions only, 14 bits (the same positions on both sides):"
echo
echo "| mesh | meshflow bytes (bits/tri) | connectivity bits/tri | Draco -cl 7 | Draco -cl 10 | meshflow / Draco 10 | progressive: bytes, base share |"
echo "|---|---:|---:|---:|---:|---:|---:|"
for m in "${meshes[@]}"; do
  # The same positions for both: meshflow's 14-bit decode of the mesh, without attributes.
  "$tool" compress "$work/$m.ply" "$work/$m.q.mfc" --bits 14 --no-normals --no-colors -q
  "$tool" decompress "$work/$m.q.mfc" "$work/$m.pos.ply" -q
  doc=$("$tool" compress "$work/$m.pos.ply" "$work/$m.mfc" --bits 14 --json)
  prog=$("$tool" compress "$work/$m.pos.ply" "$work/$m.p.mfc" --bits 14 --progressive --json)
  draco_encoder -i "$work/$m.pos.ply" -o "$work/$m.drc" -qp 14 -cl 7 > /dev/null
  draco_encoder -i "$work/$m.pos.ply" -o "$work/$m.10.drc" -qp 14 -cl 10 > /dev/null
  $py - "$m" "$doc" "$prog" "$(size "$work/$m.drc")" "$(size "$work/$m.10.drc")" <<'PY'
import json, sys
m, doc, prog, d7, d10 = sys.argv[1], json.loads(sys.argv[2]), json.loads(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
tri, b = doc["triangles"], doc["bytes"]
print(f"| {m} | {b:,} ({8.0 * b / tri:.2f}) | {doc['connectivity_bits_per_triangle']:.2f} | {d7:,} | "
      f"{d10:,} | {b / d10:.3f} | {prog['bytes']:,}, {100.0 * prog['base_bytes'] / prog['bytes']:.1f} % |")
PY
done
