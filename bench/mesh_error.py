#!/usr/bin/env python3
"""Errors of a decoded mesh against the mesh that was compressed: each decoded vertex matched to
the nearest input vertex (coders renumber vertices), then the largest position error (mm, per
axis) and the angle between decoded and input normals (degrees: mean, 99th percentile, max). Input
vertices within two 14-bit grid steps of a decoded one are told apart by normals and colours.
Prints one JSON object. Used by bench/compress_vs_draco.sh on meshflow's and Draco's decodes.
  mesh_error.py INPUT.ply DECODED.ply"""
import json
import sys

import numpy as np

TYPES = {"float": "<f4", "float32": "<f4", "double": "<f8", "uchar": "u1", "uint8": "u1",
         "char": "i1", "int": "<i4", "int32": "<i4", "uint": "<u4", "uint32": "<u4",
         "short": "<i2", "ushort": "<u2"}


def read_ply(path):
    """Vertices of a binary little-endian PLY as a dict of named columns."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    if "format binary_little_endian 1.0" not in header:
        sys.exit(f"{path}: only binary little-endian PLY is read here")
    count, props, in_vertex = 0, [], False
    for line in header:
        w = line.split()
        if w[:2] == ["element", "vertex"]:
            count, in_vertex = int(w[2]), True
        elif w[:1] == ["element"]:
            in_vertex = False
        elif w[:1] == ["property"] and in_vertex:
            props.append((w[2], TYPES[w[1]]))
    v = np.frombuffer(data, dtype=np.dtype(props), count=count, offset=end)
    return {name: v[name].astype(np.float64) for name, _ in props}


def nearest(src, dst, cell, fa, fb, tie):
    """For each dst point, the index of the nearest src point within 1.5 cells (else -1). Input
    vertices within `tie` of a decoded one (a reconstruction's near-coincident vertices, which
    quantisation makes coincident for both coders) are told apart (the second array; the first
    is the plain nearest, for position errors) by their attribute rows (fa
    input, fb decoded: normals and colours) when there are any."""
    keys = {}
    for i, k in enumerate(map(tuple, np.floor(src / cell).astype(np.int64))):
        keys.setdefault(k, []).append(i)
    out = np.full(len(dst), -1, dtype=np.int64)
    plain = np.full(len(dst), -1, dtype=np.int64)
    offsets = [(a, b, c) for a in (-1, 0, 1) for b in (-1, 0, 1) for c in (-1, 0, 1)]
    for j, (p, k) in enumerate(zip(dst, np.floor(dst / cell).astype(np.int64))):
        best, d_best, close = -1, np.inf, []
        for o in offsets:
            for i in keys.get((k[0] + o[0], k[1] + o[1], k[2] + o[2]), ()):
                d = ((src[i] - p) ** 2).sum()
                if d < d_best:
                    best, d_best = i, d
                if d <= tie * tie:
                    close.append(i)
        plain[j] = best
        if len(close) > 1 and fa is not None:
            best = close[int(np.argmin(((fa[close] - fb[j]) ** 2).sum(1)))]
        out[j] = best
    return plain, out


def main():
    a, b = read_ply(sys.argv[1]), read_ply(sys.argv[2])
    pa = np.stack([a["x"], a["y"], a["z"]], 1)
    pb = np.stack([b["x"], b["y"], b["z"]], 1)
    extent = (pa.max(0) - pa.min(0)).max()
    cols = [c for c in ("nx", "ny", "nz", "red", "green", "blue") if c in a and c in b]
    scale = np.array([1.0 if c[0] == "n" else 1.0 / 255 for c in cols])
    fa = np.stack([a[c] for c in cols], 1) * scale if cols else None
    fb = np.stack([b[c] for c in cols], 1) * scale if cols else None
    # Ties: within two steps of a 14-bit grid over the box.
    plain, match = nearest(pa, pb, extent / 2**12, fa, fb, extent / 2**13)
    ok = match >= 0
    out = {"vertices": len(pb), "unmatched": int((~ok).sum()),
           "max_position_error_mm": float(np.abs(pa[plain[ok]] - pb[ok]).max() * 1e3)}
    if "nx" in a and "nx" in b:
        na = np.stack([a["nx"], a["ny"], a["nz"]], 1)[match[ok]]
        nb = np.stack([b["nx"], b["ny"], b["nz"]], 1)[ok]
        na /= np.linalg.norm(na, axis=1, keepdims=True)
        nb /= np.linalg.norm(nb, axis=1, keepdims=True)
        deg = np.degrees(np.arccos(np.clip((na * nb).sum(1), -1, 1)))
        out.update(normal_mean_deg=float(deg.mean()), normal_p99_deg=float(np.percentile(deg, 99)),
                   normal_max_deg=float(deg.max()))
    if "red" in a and "red" in b:
        ca = np.stack([a["red"], a["green"], a["blue"]], 1)[match[ok]]
        cb = np.stack([b["red"], b["green"], b["blue"]], 1)[ok]
        out["max_color_error"] = int(np.abs(ca - cb).max())
    print(json.dumps(out))


main()
