#!/usr/bin/env python3
"""Checks that a screenshot of the viewer page shows a mesh: at least half of the pixels of the
picture's middle differ from the page's background (#20242a). Reads the PNG with the standard
library only (zlib), so the browser tests need no imaging package.

usage: screenshot_check.py PAGE_PNG   (exit 1 when the middle is background)
"""
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
