#!/usr/bin/env bash
# A run in a real browser: `meshflow run --fuse --serve` fuses meshflow's own synthetic depth
# sequence (no shared data) while headless Chromium watches from the start. When the run is over
# the page must be complete and show the triangle and vertex counts of the fused.ply the run
# wrote (read from its header here), a screenshot must show the mesh, and fused.ply must be byte
# for byte the one a run without --serve writes. Twice: with --optimize none the page's counts
# are those of the map's blocks as it assembled them (serve/map_publisher.h); with the default
# optimisation the final mesh comes as a whole after the blocks. The first case replays its
# frames 60 times, paced at 20 Hz with --serve only (--rate's queue policy must leave fused.ply
# as it is), and the page must have recorded the live map's latency (serve/map_publisher.h:
# map_shown) for frames it saw: each frame at most once, in order, its total from entering the graph to
# the page's draw no less than the server's share, both non-negative, and under a minute.
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

# run_case NAME FRAMES SERVED_ARGS ARGS...: one served run with a viewer (SERVED_ARGS on it
# only; FRAMES it feeds), checked as above.
run_case() {
  local name=$1 frames=$2 served_args=$3
  shift 3
  local dir="$work/$name"
  mkdir -p "$dir"
  local run=(run --synthetic-depth --synthetic-size 160x120 --synthetic-frames 6 --fuse
             --voxel 0.05 "$@")
  "$meshflow" "${run[@]}" -o "$dir/plain" > "$dir/plain.log"
  # shellcheck disable=SC2086
  "$meshflow" "${run[@]}" $served_args -o "$dir/served" --serve 0 --exit-after 90 \
    > "$dir/served.log" 2>&1 &
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
  python3 - "$dir/page.json" "$name" "$frames" "$served_args" <<'PY' || status=1
import json, sys
d = json.load(open(sys.argv[1]))
name, frames = sys.argv[2], sys.argv[3]
if d.get("frames") != frames:
    sys.exit(f"FAIL: {name}: the page's stats counted {d.get('frames')} frames, not {frames}")
if int(d.get("blocks", 0)) == 0:
    sys.exit(f"FAIL: {name}: the page got no block of the map")
print(f"{name}: the page holds {d['blocks']} blocks, drew {d.get('levels')} times")
if "--rate" in sys.argv[4]:
    rows = [[float(x) for x in r.split(":")] for r in d.get("mapLatencies", "").split(",") if r]
    if not rows:
        sys.exit(f"FAIL: {name}: the page recorded no map latency")
    seqs = [int(r[0]) for r in rows]
    if seqs != sorted(set(seqs)) or max(seqs) >= int(frames):
        sys.exit(f"FAIL: {name}: frames listed twice, out of order or unknown: {seqs}")
    for seq, entered, total, server in rows:
        if not (0 <= server <= total + 5 and total < 60000):  # (5 ms: two clocks read)
            sys.exit(f"FAIL: {name}: frame {seq:.0f}: total {total} ms, server {server} ms")
    totals = sorted(r[2] for r in rows)
    print(f"{name}: map latency of {len(rows)} frames: p50 {totals[len(totals) // 2]:.0f} ms")
PY
  cleanup
}

run_case blocks 360 "--rate 20" --optimize none --loops 60
run_case final 6 ""
[ $status -eq 0 ] || exit 1
echo "PASS: the page shows fused.ply's counts, from the map's blocks and from the final mesh"
