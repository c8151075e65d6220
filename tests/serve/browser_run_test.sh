#!/usr/bin/env bash
# A run in a real browser: `meshflow run --fuse --serve` fuses meshflow's own synthetic depth
# sequence (no shared data) while headless Chromium watches from the start. When the run is over
# the page must be complete and show the triangle and vertex counts of the fused.ply the run
# wrote (read from its header here), a screenshot must show the mesh, and fused.ply must be byte
# for byte the one a run without --serve writes. Twice: with --optimize none the page's counts
# are those of the map's blocks as it assembled them (serve/map_publisher.h); with the default
# optimisation the final mesh comes as a whole after the blocks.
#
# usage: browser_run_test.sh MESHFLOW_BINARY WORK_DIR
set -euo pipefail
meshflow=$1
work=$2
source "$(dirname "$0")/browser_common.sh"
rm -rf "$work"
mkdir -p "$work"
status=0
server=""
cleanup() {
  [ -z "$server" ] && return
  kill "$server" 2>/dev/null || true
  wait "$server" 2>/dev/null || true
  server=""
}
trap cleanup EXIT

# run_case NAME ARGS...: one served run with a viewer, checked as above.
run_case() {
  local name=$1
  shift
  local dir="$work/$name"
  mkdir -p "$dir"
  local run=(run --synthetic-depth --synthetic-size 160x120 --synthetic-frames 6 --fuse
             --voxel 0.05 "$@")
  "$meshflow" "${run[@]}" -o "$dir/plain" > "$dir/plain.log"
  "$meshflow" "${run[@]}" -o "$dir/served" --serve 0 --exit-after 90 > "$dir/served.log" 2>&1 &
  server=$!
  local url
  url=$(wait_url "$dir/served.log" "$server")
  if [ -z "$url" ]; then
    echo "FAIL: $name: meshflow run --serve printed no URL:" >&2
    cat "$dir/served.log" >&2
    status=1
    cleanup
    return
  fi
  echo "$name: serving at $url"
  # A viewer from the start: the page is complete only after the run wrote fused.ply and
  # published the end.
  if ! load_page "$url" "$dir"; then
    status=1
    cleanup
    return
  fi
  local vertices triangles
  read -r vertices triangles < <(ply_counts "$dir/served/fused.ply")
  echo "$name: fused.ply: $vertices vertices, $triangles triangles"
  check_page "$dir" "$vertices" "$triangles" 1 || { echo "FAIL: $name (above)" >&2; status=1; }
  cmp "$dir/plain/fused.ply" "$dir/served/fused.ply" ||
    { echo "FAIL: $name: fused.ply differs with --serve and a viewer" >&2; status=1; }
  python3 - "$dir/page.json" "$name" <<'PY' || status=1
import json, sys
d = json.load(open(sys.argv[1]))
if d.get("frames") != "6":
    sys.exit(f"FAIL: {sys.argv[2]}: the page's stats counted {d.get('frames')} frames, not 6")
if int(d.get("blocks", 0)) == 0:
    sys.exit(f"FAIL: {sys.argv[2]}: the page got no block of the map")
print(f"{sys.argv[2]}: the page holds {d['blocks']} blocks, drew {d.get('levels')} times")
PY
  cleanup
}

run_case blocks --optimize none
run_case final
[ $status -eq 0 ] || exit 1
echo "PASS: the page shows fused.ply's counts, from the map's blocks and from the final mesh"
