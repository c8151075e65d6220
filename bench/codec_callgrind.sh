#!/usr/bin/env bash
# Load-independent codec speed: callgrind instruction counts of meshflow's .mfc coder and Draco
# 1.5.5's tools on the same meshes (the demo room and kurt3d scan000 at 5 cm with normals, the
# Kinect mug reconstructed with normals and colours), counting only the codec call
# (decompress_mesh / compress_mesh; Draco's Decoder::DecodeMeshFromBuffer /
# ExpertEncoder::EncodeToBuffer), not file reading or writing. As written: 14-bit positions,
# Draco's default normals (-qn 10) and meshflow's at the equal-error --normal-error of
# bench/compress_vs_draco.sh (room 0.6, kurt3d 0.8, Kinect 0.6 degrees), colours exact. Positions
# only: both without normals and colours (Draco reads a positions-only PLY). Prints markdown rows;
# ratio = Draco's instructions / meshflow's (> 1: meshflow faster).
#   bench/codec_callgrind.sh [BUILD_DIR]     (needs valgrind, taskset and the `draco` package)
set -euo pipefail
cd "$(dirname "$0")/.."
tool="$(pwd)/${1:-build}/meshflow"
data=${MESHFLOW_DATA:-../shared/data}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
command -v valgrind > /dev/null || { echo "needs valgrind" >&2; exit 2; }
command -v draco_encoder > /dev/null || { echo "needs draco_encoder (apt-get install draco)" >&2; exit 2; }
cd "$work"
# Instructions of the calls matching $1 while running the rest, on one core: callgrind counts
# a call on its own thread only, and the decoder hands independent jobs to a second thread where
# oneTBB has one (nodes/compress/side_by_side.h); on one core it runs them itself, so every
# instruction of the call is counted.
count() {
  local toggle=$1
  shift
  taskset -c 0 valgrind --tool=callgrind --callgrind-out-file=cg.out --toggle-collect="$toggle" "$@" \
    > /dev/null 2> cg.log
  grep -o 'refs: *[0-9,]*' cg.log | tr -dc '0-9'
}
mf_dec='meshflow::compress::decompress_mesh*'
mf_enc='meshflow::compress::compress_mesh*'
dr_dec='draco::Decoder::DecodeMeshFromBuffer*'
dr_enc='draco::ExpertEncoder::EncodeToBuffer*'

"$tool" demo -o room.ply -q
meshes=(room:0.6)
if [ -f "$data/kurt3d/scan000.3d" ]; then
  "$tool" reconstruct "$data/kurt3d/scan000.3d" --voxel 0.05 -o kurt3d.ply -q
  meshes+=(kurt3d:0.8)
fi
kinect="$data/kinect_pcl/table_scene_mug_stereo_textured.pcd"
if [ -f "$kinect" ]; then
  "$tool" reconstruct "$kinect" -o kinect.ply -q
  meshes+=(kinect:0.6)
fi
ratio() { python3 -c "import sys; print(f'{int(sys.argv[1]) / int(sys.argv[2]):.2f}')" "$1" "$2"; }
mega() { python3 -c "import sys; print(f'{int(sys.argv[1]) / 1e6:.1f}')" "$1"; }
echo "| mesh, coding | meshflow decode / encode (M instr.) | Draco -cl 7 decode / encode | decode ratio | encode ratio |"
echo "|---|---:|---:|---:|---:|"
for m in "${meshes[@]}"; do
  n=${m%%:*}
  e=${m##*:}
  "$tool" compress "$n.ply" "$n.mfc" --bits 14 --normal-error "$e" -q
  "$tool" compress "$n.ply" "$n.pos.mfc" --bits 14 --no-normals --no-colors -q
  "$tool" decompress "$n.pos.mfc" "$n.pos.ply" -q
  draco_encoder -i "$n.ply" -o "$n.drc" -qp 14 -cl 7 > /dev/null
  draco_encoder -i "$n.pos.ply" -o "$n.pos.drc" -qp 14 -cl 7 > /dev/null
  for kind in written positions; do
    if [ $kind = written ]; then
      mfc=$n.mfc; drc=$n.drc; ply=$n.ply; opts=(--normal-error "$e")
    else
      mfc=$n.pos.mfc; drc=$n.pos.drc; ply=$n.pos.ply; opts=(--no-normals --no-colors)
    fi
    md=$(count "$mf_dec" "$tool" decompress "$mfc" out.ply -q)
    me=$(count "$mf_enc" "$tool" compress "$ply" out.mfc --bits 14 "${opts[@]}" -q)
    dd=$(count "$dr_dec" draco_decoder -i "$drc" -o out.ply)
    de=$(count "$dr_enc" draco_encoder -i "$ply" -o out.drc -qp 14 -cl 7)
    echo "| $n, $kind | $(mega "$md") / $(mega "$me") | $(mega "$dd") / $(mega "$de") |" \
      "$(ratio "$dd" "$md")× | $(ratio "$de" "$me")× |"
  done
done
