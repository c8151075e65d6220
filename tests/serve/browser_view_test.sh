#!/usr/bin/env bash
# The viewer page in a real browser: `meshflow view` serves a reconstructed sphere on 127.0.0.1,
# headless Chromium loads the page, the page decodes the stream with the WebAssembly decoder, and
# the test checks that the page reports the triangle and vertex counts of the PLY file (read from
# its header here, not by meshflow) and that a screenshot shows the mesh (pixels differ from the
# background in the middle of the picture). Chromium is driven by browser_check.py.
#
# usage: browser_view_test.sh MESHFLOW_BINARY WORK_DIR
# Fails (never skips) when Chromium or Python 3 is missing: scripts/install_deps.sh installs them.
set -euo pipefail
meshflow=$1
work=$2
here=$(cd "$(dirname "$0")" && pwd)
rm -rf "$work"
mkdir -p "$work"

chromium=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$chromium" ]; then
  echo "FAIL: no chromium on PATH: the browser test needs Debian's chromium" \
       "(scripts/install_deps.sh installs it)" >&2
  exit 1
fi
if ! command -v python3 >/dev/null; then
  echo "FAIL: no python3 on PATH (the screenshot check needs it)" >&2
  exit 1
fi

"$meshflow" sample sphere --points 20000 -o "$work/sphere.ply" >/dev/null
"$meshflow" reconstruct "$work/sphere.ply" -o "$work/mesh.ply" >/dev/null
header=$(head -c 2048 "$work/mesh.ply" | tr -d '\r' | sed -n '1,/^end_header/p' | tr -d '\000')
vertices=$(sed -n 's/^element vertex \([0-9]*\)$/\1/p' <<<"$header")
triangles=$(sed -n 's/^element face \([0-9]*\)$/\1/p' <<<"$header")
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
url=""
for _ in $(seq 1 200); do
  url=$(sed -n 's/^url \(http:[^ ]*\)$/\1/p' "$work/view.log")
  [ -n "$url" ] && break
  kill -0 "$server" 2>/dev/null || break
  sleep 0.1
done
if [ -z "$url" ]; then
  echo "FAIL: meshflow view printed no URL:" >&2
  cat "$work/view.log" >&2
  exit 1
fi
echo "serving at $url"
case "$url" in
  http://127.0.0.1:*) ;;
  *) echo "FAIL: --serve PORT did not bind 127.0.0.1: $url" >&2; exit 1 ;;
esac

# Chromium through the DevTools protocol (browser_check.py): it waits for the page's own
# data-state instead of a fixed time, then takes the screenshot.
status=0
if ! timeout 120 python3 "$here/browser_check.py" "$chromium" "$url" "$work/page.json" \
    "$work/page.png" 90; then
  echo "FAIL: the page did not load (Chromium's log: $work/page.json.chromium.log)" >&2
  exit 1
fi
read -r state page_triangles page_vertices levels < <(python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
print(d.get("state", "-"), d.get("triangles", "-"), d.get("vertices", "-"), d.get("levels", 0))' \
  "$work/page.json")
if [ "$levels" -lt 2 ]; then
  echo "FAIL: the page drew $levels level(s): no coarser level before the full mesh" >&2
  status=1
fi
if [ "$state" != complete ]; then
  echo "FAIL: the page's state is '$state', not complete" >&2
  status=1
fi
if [ "$page_triangles" != "$triangles" ] || [ "$page_vertices" != "$vertices" ]; then
  echo "FAIL: the page shows $page_triangles triangles, $page_vertices vertices;" \
       "the file has $triangles and $vertices" >&2
  status=1
fi

python3 - "$work/page.png" <<'EOF' || status=1
# Counts the pixels of the screenshot's middle that differ from the page's background (#20242a).
import struct, sys, zlib
data = open(sys.argv[1], "rb").read()
assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
pos, chunks = 8, {}
idat = b""
while pos < len(data):
    n, kind = struct.unpack(">I4s", data[pos:pos + 8])
    body = data[pos + 8:pos + 8 + n]
    if kind == b"IHDR":
        w, h, depth, color = struct.unpack(">IIBB", body[:10])
    elif kind == b"IDAT":
        idat += body
    pos += 12 + n
assert depth == 8 and color in (2, 6), f"PNG depth {depth}, colour type {color}"
bpp = 3 if color == 2 else 4
raw = zlib.decompress(idat)
stride = w * bpp
rows, prev, at = [], bytearray(stride), 0
for y in range(h):
    f = raw[at]; line = bytearray(raw[at + 1:at + 1 + stride]); at += 1 + stride
    for i in range(stride):
        a = line[i - bpp] if i >= bpp else 0
        b = prev[i]; c = prev[i - bpp] if i >= bpp else 0
        if f == 1: line[i] = (line[i] + a) & 255
        elif f == 2: line[i] = (line[i] + b) & 255
        elif f == 3: line[i] = (line[i] + (a + b) // 2) & 255
        elif f == 4:
            p = a + b - c; pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
    rows.append(line); prev = line
bg = (0x20, 0x24, 0x2a)
x0, x1, y0, y1 = w * 3 // 8, w * 5 // 8, h * 3 // 8, h * 5 // 8
differ = total = 0
for y in range(y0, y1):
    for x in range(x0, x1):
        px = rows[y][x * bpp:x * bpp + 3]
        total += 1
        differ += max(abs(px[k] - bg[k]) for k in range(3)) > 12
share = differ / total
print(f"screenshot {w}x{h}: {100 * share:.1f} % of the middle differs from the background")
if share < 0.5:
    print("FAIL: the mesh is not in the middle of the screenshot", file=sys.stderr)
    sys.exit(1)
EOF

cleanup
trap - EXIT
cat "$work/view.log"
if [ $status -ne 0 ]; then
  echo "Chromium's log: $work/page.json.chromium.log" >&2
  exit 1
fi
echo "PASS: the page shows $triangles triangles and $vertices vertices, as mesh.ply has"
