#!/usr/bin/env bash
# A run in a real browser: `meshflow run --fuse --serve` fuses meshflow's own synthetic depth
# sequence (no shared data) while headless Chromium watches; when the run is over the page must
# be complete and show the triangle and vertex counts of the fused.ply the run wrote (read from
# its header here), a screenshot must show the mesh, and fused.ply must be byte for byte the one
# a run without --serve writes.
#
# usage: browser_run_test.sh MESHFLOW_BINARY WORK_DIR
set -euo pipefail
meshflow=$1
work=$2
source "$(dirname "$0")/browser_common.sh"
rm -rf "$work"
mkdir -p "$work"

run=(run --synthetic-depth --synthetic-size 160x120 --synthetic-frames 6 --fuse --voxel 0.05)
"$meshflow" "${run[@]}" -o "$work/plain" > "$work/plain.log"
"$meshflow" "${run[@]}" -o "$work/served" --serve 0 --exit-after 90 > "$work/served.log" 2>&1 &
server=$!
cleanup() {
  kill "$server" 2>/dev/null || true
  wait "$server" 2>/dev/null || true
}
trap cleanup EXIT
url=$(wait_url "$work/served.log" "$server")
if [ -z "$url" ]; then
  echo "FAIL: meshflow run --serve printed no URL:" >&2
  cat "$work/served.log" >&2
  exit 1
fi
echo "serving at $url"
status=0
# A viewer from the start: the page is complete only after the run wrote fused.ply and
# published its mesh.
load_page "$url" "$work" || status=1
read -r vertices triangles < <(ply_counts "$work/served/fused.ply")
echo "fused.ply: $vertices vertices, $triangles triangles"
[ -n "$vertices" ] && [ -n "$triangles" ] || { echo "FAIL: no counts in fused.ply" >&2; exit 1; }
[ $status -ne 0 ] || check_page "$work" "$vertices" "$triangles" 1 || status=1
if ! cmp "$work/plain/fused.ply" "$work/served/fused.ply"; then
  echo "FAIL: fused.ply differs with --serve and a viewer" >&2
  status=1
fi
frames=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1])).get("frames", 0))' \
  "$work/page.json")
if [ "$frames" != 6 ]; then
  echo "FAIL: the page's stats counted $frames frames, not 6" >&2
  status=1
fi
cleanup
trap - EXIT
cat "$work/served.log"
[ $status -eq 0 ] || exit 1
echo "PASS: the page shows $triangles triangles and $vertices vertices, as fused.ply has"
