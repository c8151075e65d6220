#!/usr/bin/env bash
# Sizes of meshflow's compressed meshes beside Draco's (Debian's draco tools) on the same
# positions-only meshes at 14-bit quantisation: the demo room, kurt3d scan000 at 5 cm and the
# fused Redwood map at 1 cm (made here from $MESHFLOW_DATA; the room alone without it).
# Prints one markdown table row per mesh. Speed: bench/nodes/bench_compress.cpp (in-process).
#   bench/compress_vs_draco.sh [BUILD_DIR]     (needs the `draco` package: draco_encoder)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
tool="$build/meshflow"
data=${MESHFLOW_DATA:-../shared/data}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
command -v draco_encoder > /dev/null || { echo "needs draco_encoder (apt-get install draco)" >&2; exit 2; }

"$tool" demo -o "$work/room.ply" -q
meshes=(room)
if [ -f "$data/kurt3d/scan000.3d" ]; then
  "$tool" reconstruct "$data/kurt3d/scan000.3d" --voxel 0.05 -o "$work/kurt3d.ply" -q
  meshes+=(kurt3d)
fi
if [ -d "$data/rgbd_redwood" ]; then
  "$tool" run "$data/rgbd_redwood" --fuse --voxel 0.01 -o "$work/redwood" -q
  mv "$work/redwood/fused.ply" "$work/redwood.ply"
  meshes+=(redwood)
fi

json() { python3 -c "import json,sys; print(json.load(sys.stdin)$1)"; }
echo "| mesh | triangles | meshflow bytes (bits/tri) | connectivity bits/tri | Draco -cl 7 bytes (bits/tri) | Draco connectivity bits/tri | Draco -cl 10 bytes | meshflow / Draco 7 | progressive: bytes, base share |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|"
for m in "${meshes[@]}"; do
  # The same positions for both: meshflow's 14-bit decode of the mesh, without attributes.
  "$tool" compress "$work/$m.ply" "$work/$m.q.mfc" --bits 14 --no-normals --no-colors -q
  "$tool" decompress "$work/$m.q.mfc" "$work/$m.pos.ply" -q
  doc=$("$tool" compress "$work/$m.pos.ply" "$work/$m.mfc" --bits 14 --json)
  tri=$(json "['triangles']" <<<"$doc")
  bytes=$(json "['bytes']" <<<"$doc")
  conn=$(json "['connectivity_bits_per_triangle']" <<<"$doc")
  prog=$("$tool" compress "$work/$m.pos.ply" "$work/$m.p.mfc" --bits 14 --progressive --json)
  pbytes=$(json "['bytes']" <<<"$prog")
  pbase=$(json "['base_bytes']" <<<"$prog")
  draco_encoder -i "$work/$m.pos.ply" -o "$work/$m.drc" -qp 14 -cl 7 > /dev/null
  draco_encoder -i "$work/$m.pos.ply" -o "$work/$m.q1.drc" -qp 1 -cl 7 > /dev/null
  draco_encoder -i "$work/$m.pos.ply" -o "$work/$m.10.drc" -qp 14 -cl 10 > /dev/null
  d7=$(stat -c %s "$work/$m.drc")
  d1=$(stat -c %s "$work/$m.q1.drc")
  d10=$(stat -c %s "$work/$m.10.drc")
  python3 - "$m" "$tri" "$bytes" "$conn" "$d7" "$d1" "$d10" "$pbytes" "$pbase" <<'PY'
import sys
m, tri, b, conn, d7, d1, d10, pb, pbase = sys.argv[1:]
tri, b, conn, d7, d1, d10, pb, pbase = int(tri), int(b), float(conn), int(d7), int(d1), int(d10), int(pb), int(pbase)
bpt = lambda x: 8.0 * x / tri
print(f"| {m} | {tri:,} | {b:,} ({bpt(b):.2f}) | {conn:.2f} | {d7:,} ({bpt(d7):.2f}) | {bpt(d1):.2f} | {d10:,} | {b / d7:.3f} | {pb:,}, {100.0 * pbase / pb:.1f} % |")
PY
done
echo
echo "Draco's connectivity: its file with 1-bit positions (an upper bound: the positions still cost a little)."
