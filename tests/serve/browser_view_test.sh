#!/usr/bin/env bash
# The viewer page in a real browser: `meshflow view` serves a reconstructed sphere on 127.0.0.1,
# headless Chromium loads the page, the page decodes the stream with the WebAssembly decoder, and
# the test checks that the page reports the triangle and vertex counts of the PLY file (read from
# its header here, not by meshflow) and that a screenshot shows the mesh (pixels differ from the
# background in the middle of the picture). Chromium is driven by browser_check.py.
#
# usage: browser_view_test.sh MESHFLOW_BINARY WORK_DIR
set -euo pipefail
meshflow=$1
work=$2
source "$(dirname "$0")/browser_common.sh"
rm -rf "$work"
mkdir -p "$work"

"$meshflow" sample sphere --points 20000 -o "$work/sphere.ply" >/dev/null
"$meshflow" reconstruct "$work/sphere.ply" -o "$work/mesh.ply" >/dev/null
read -r vertices triangles < <(ply_counts "$work/mesh.ply")
echo "mesh.ply: $vertices vertices, $triangles triangles"
[ -n "$vertices" ] && [ -n "$triangles" ] || { echo "FAIL: no counts in mesh.ply's header" >&2; exit 1; }

# view_at RATE MIN_LEVELS REFINE: serves mesh.ply at RATE Mbit/s, loads the page and checks it
# (counts, screenshot, at least MIN_LEVELS levels drawn, refined by REFINE: the page's
# data-refine, what the server chose).
view_at() {
  local rate=$1 min_levels=$2 refine=$3 status=0
  "$meshflow" view "$work/mesh.ply" --serve 0 --exit-after 90 --chunk-kb 4 --serve-rate "$rate" \
    > "$work/view.log" 2>&1 &
  server=$!
  trap cleanup EXIT
  url=$(wait_url "$work/view.log" "$server")
  if [ -z "$url" ]; then
    echo "FAIL: meshflow view printed no URL:" >&2
    cat "$work/view.log" >&2
    return 1
  fi
  echo "serving at $url ($rate Mbit/s)"
  load_page "$url" "$work" && check_page "$work" "$vertices" "$triangles" "$min_levels" || status=1
  local page_refine
  page_refine=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1])).get("refine"))' \
    "$work/page.json" 2>/dev/null || true)
  if [ "$page_refine" != "$refine" ]; then
    echo "FAIL: the base was refined by '$page_refine', not $refine" >&2
    status=1
  fi
  cleanup
  trap - EXIT
  cat "$work/view.log"
  return $status
}
cleanup() {
  kill "$server" 2>/dev/null || true
  wait "$server" 2>/dev/null || true
}

# 1 Mbit/s: the single-rate image (about 40 kB) comes within a second, so it follows the base;
# the page draws the base, then the full mesh.
view_at 1 2 single_rate || exit 1
# 0.1 Mbit/s: it would take over 3 s, so the split packets follow the base (the whole 120 kB
# stream in about 10 s) and the page draws finer levels before the full one.
view_at 0.1 3 packets || exit 1
echo "PASS: the page shows $triangles triangles and $vertices vertices, as mesh.ply has"
