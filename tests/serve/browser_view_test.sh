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

# 1 Mbit/s: the 120 kB stream takes about a second, so the page shows the base mesh and
# finer levels before the full one (data-levels counts the levels it drew).
"$meshflow" view "$work/mesh.ply" --serve 0 --exit-after 90 --chunk-kb 4 --serve-rate 1 \
  > "$work/view.log" 2>&1 &
server=$!
cleanup() {
  kill "$server" 2>/dev/null || true
  wait "$server" 2>/dev/null || true
}
trap cleanup EXIT
url=$(wait_url "$work/view.log" "$server")
if [ -z "$url" ]; then
  echo "FAIL: meshflow view printed no URL:" >&2
  cat "$work/view.log" >&2
  exit 1
fi
echo "serving at $url"
status=0
load_page "$url" "$work" && check_page "$work" "$vertices" "$triangles" 2 || status=1
cleanup
trap - EXIT
cat "$work/view.log"
[ $status -eq 0 ] || exit 1
echo "PASS: the page shows $triangles triangles and $vertices vertices, as mesh.ply has"
