#!/usr/bin/env python3
"""What watching costs and how fast a picture comes, measured on this machine (bench/RESULTS.md,
"Viewing"). Release build; kurt3d and rgbd_redwood from MESHFLOW_DATA (default ../shared/data).

1. view: time to the first picture and to the full mesh in headless Chromium for `meshflow view`
   of kurt3d scan000 meshed at 5 cm, at --serve-rate 10 and 100 Mbit/s (the page's own numbers
   from the WebSocket's opening; the page's decode and draw times beside them), next to the time
   the same cap needs for the PLY file, a Draco file (draco_encoder -qp 14 -cl 7) and the
   single-rate .mfc (size x 8 / rate: nothing can be drawn before they are complete).
2. map: the same for the fused Redwood map (`meshflow run rgbd_redwood --fuse --optimize none
   --serve`, 1 cm voxels, its blocks once the run is over) against fused.ply and its Draco file.
3. viewers: frames/s of `meshflow run --synthetic-depth --triangulate rqt` (640 x 480) with no
   viewer, one that stopped reading (a handshake, then nothing read: a 4 kB receive buffer), and
   1 and 4 viewers that read everything (plain WebSocket clients), interleaved run by run.

4. latency: the live map's latency on the Redwood sequence replayed at 30 Hz (`meshflow run
   rgbd_redwood --fuse --optimize none --rate 30 --loops L --policy P --serve`, 1 cm voxels;
   L = 150 with realtime, 30 with queue: runs of 25 s or more, the page connects early on):
   for each frame, from its release into the graph to the page having drawn the update that
   holds it (serve/map_publisher.h: map_shown; the page's data-map-latencies), both on this
   machine's clock, p50 / p99, and the server's share (release to the update's blocks coded).
   Frames released in the page's first second are left out (they wait for the whole map the
   page is sent when it connects). The page acknowledges each round of blocks once drawn and
   the next round waits for that (serve/server.h: map_round), so frames merged into a round
   list only the newest update's. Policy realtime (a late source skips to the newest frame)
   and queue (every frame, late).

usage: serve_bench.py BUILD_DIR [RUNS] [view,map,viewers,latency]
"""
import base64
import json
import os
import re
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time

build = sys.argv[1]
runs = int(sys.argv[2]) if len(sys.argv) > 2 else 3
parts = set((sys.argv[3] if len(sys.argv) > 3 else "view,map,viewers,latency").split(","))
RATES = (10, 100)
here = os.path.dirname(os.path.abspath(__file__))
source = os.path.dirname(os.path.dirname(here))
meshflow = os.path.join(build, "meshflow")
data = os.environ.get("MESHFLOW_DATA", os.path.join(source, "..", "shared", "data"))
check = os.path.join(source, "tests", "serve", "browser_check.py")
chromium = shutil.which("chromium") or shutil.which("chromium-browser")
draco = shutil.which("draco_encoder")
work = tempfile.mkdtemp(prefix="meshflow-serve-bench-")


def start(args):
    """Starts meshflow with --serve 0; returns (process, url, stdout file) once it printed its URL
    (view on stdout, the run commands on stderr)."""
    out = open(os.path.join(work, "server.out"), "w+")
    err = open(os.path.join(work, "server.err"), "w+")
    p = subprocess.Popen([meshflow] + args, stdout=out, stderr=err, text=True)
    for _ in range(400):
        for f in (out, err):
            f.seek(0)
            for line in f.read().splitlines():
                if line.startswith("url http"):
                    return p, line.split()[1], out
        time.sleep(0.05)
    raise RuntimeError("no url: " + open(err.name).read())


def wait_json(p, log):
    """Waits until a run started with --json has printed its summary (then it serves)."""
    for _ in range(6000):
        log.seek(0)
        text = log.read()
        try:
            return json.loads(text)
        except ValueError:
            if p.poll() is not None:
                raise RuntimeError("the run ended without its summary: " + text)
        time.sleep(0.05)
    raise RuntimeError("no summary")


def page(url):
    """Loads the page in headless Chromium until it is complete; its data attributes."""
    out = os.path.join(work, "page.json")
    subprocess.run([sys.executable, check, chromium, url, out, out + ".png", "120"], check=True,
                   stdout=subprocess.DEVNULL)
    d = json.load(open(out))
    if d.get("state") != "complete":
        raise RuntimeError("the page did not complete: " + json.dumps(d))
    return d


def draco_bytes(ply):
    if not draco:
        return None
    out = os.path.join(work, "mesh.drc")
    subprocess.run([draco, "-i", ply, "-o", out, "-qp", "14", "-cl", "7"], check=True,
                   stdout=subprocess.DEVNULL)
    return os.path.getsize(out)


def at_cap(size, rate):
    return "-" if size is None else f"{size * 8 / (rate * 1e3):.0f}"


def timing_table(name, server_args, ply, extra_sizes):
    """Per cap: medians of the page's first picture, full mesh, bytes received and the full
    mesh's decode + draw, beside the files at the cap."""
    ply_bytes, draco_size = os.path.getsize(ply), draco_bytes(ply)
    sizes = f"PLY {ply_bytes} B, Draco {draco_size} B" + "".join(
        f", {k} {v} B" for k, v in extra_sizes.items())
    print(f"{name}: {sizes}")
    print("| cap | first picture (ms) | full (ms) | bytes sent | full decode + draw (ms) "
          "| PLY at the cap | Draco at the cap |"
          + "".join(f" {k} at the cap |" for k in extra_sizes))
    print("|---:|---:|---:|---:|---:|---:|---:|" + "---:|" * len(extra_sizes))
    for rate in RATES:
        rows = []
        for _ in range(runs):
            p, url, log = server_args(rate)
            d = page(url)
            p.terminate()
            p.wait()
            rows.append(d)
        med = lambda key: statistics.median(float(d.get(key, "nan")) for d in rows)
        shown = med("fullDecodeMs") + med("fullShowMs") if "fullDecodeMs" in rows[0] else float("nan")
        print(f"| {rate} Mbit/s | {med('firstMs'):.0f} | {med('fullMs'):.0f} | {med('bytes'):.0f} | "
              f"{shown:.0f} | {at_cap(ply_bytes, rate)} | {at_cap(draco_size, rate)} |"
              + "".join(f" {at_cap(v, rate)} |" for v in extra_sizes.values()))
        print("  page:", json.dumps({k: rows[-1].get(k) for k in (
            "warmMs", "firstByteMs", "lastByteMs", "decodes", "decodeMs", "renders", "renderMs",
            "levels")}))


def viewer(url, stop, read=True):
    """A WebSocket client that completes the handshake and then reads everything (or, with
    read=False, nothing: a 4 kB receive buffer, never read)."""
    host, port = url.split("//")[1].rstrip("/").split(":")
    s = socket.socket()
    if not read:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    s.connect((host, int(port)))
    key = base64.b64encode(os.urandom(16)).decode()
    s.sendall((f"GET /ws HTTP/1.1\r\nHost: {host}\r\nUpgrade: websocket\r\n"
               f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
               "Sec-WebSocket-Version: 13\r\n\r\n").encode())
    s.settimeout(0.2)
    while not stop.is_set():
        if not read:
            time.sleep(0.05)
            continue
        try:
            if not s.recv(1 << 16):
                break
        except socket.timeout:
            pass
    s.close()


# 1. kurt3d in meshflow view
if "view" in parts:
    scan = os.path.join(data, "kurt3d", "scan000.3d")
    mesh = os.path.join(work, "kurt3d.ply")
    subprocess.run([meshflow, "reconstruct", scan, "--voxel", "0.05", "-o", mesh], check=True,
                   stdout=subprocess.DEVNULL)
    mfc = os.path.join(work, "kurt3d.mfc")
    subprocess.run([meshflow, "reconstruct", scan, "--voxel", "0.05", "-o", mfc], check=True,
                   stdout=subprocess.DEVNULL)
    timing_table("kurt3d scan000 at 5 cm (meshflow view)",
                 lambda rate: start(["view", mesh, "--serve", "0", "--serve-rate", str(rate),
                                     "--chunk-kb", "16", "--exit-after", "120"]),
                 mesh, {".mfc": os.path.getsize(mfc)})

# 2. the fused Redwood map, after the run
if "map" in parts:
    redwood = os.path.join(data, "rgbd_redwood")
    fused = os.path.join(work, "fused")

    def run_map(rate):
        p, url, log = start(["run", redwood, "--fuse", "--optimize", "none", "-o", fused,
                             "--json", "--serve", "0", "--serve-rate", str(rate),
                             "--exit-after", "300"])
        wait_json(p, log)
        return p, url, log

    p, _, _ = run_map(100)  # fused.ply for the sizes
    p.terminate()
    p.wait()
    timing_table("fused Redwood map, 1 cm (run --fuse --optimize none --serve)", run_map,
                 os.path.join(fused, "fused.ply"), {})

# 3. frames/s with no viewer, a stalled one, 1 and 4 reading viewers (interleaved)
if "viewers" in parts:
    cases = (("none", 0, True), ("1 stalled", 1, False), ("1", 1, True), ("4", 4, True))
    rates = {c[0]: [] for c in cases}
    for _ in range(runs):
        for label, viewers, read in cases:
            p, url, log = start(["run", "--synthetic-depth", "--synthetic-frames", "120",
                                 "--triangulate", "rqt", "-o", os.path.join(work, "run"), "--json",
                                 "--serve", "0", "--exit-after", "0.01"])
            stop = threading.Event()
            threads = [threading.Thread(target=viewer, args=(url, stop, read))
                       for _ in range(viewers)]
            for t in threads:
                t.start()
            p.wait()
            log.seek(0)
            doc = json.loads(log.read())
            stop.set()
            for t in threads:
                t.join()
            rates[label].append(doc["frames_per_second"])
    print("| viewers | frames/s (median of runs) | runs |")
    print("|---|---:|---|")
    for label, _, _ in cases:
        r = rates[label]
        print(f"| {label} | {statistics.median(r):.1f} | {', '.join(f'{x:.1f}' for x in r)} |")

def percentile(values, q):
    s = sorted(values)
    return s[min(len(s) - 1, int(q * len(s)))] if s else float("nan")


# 4. the live map's latency at 30 Hz
if "latency" in parts:
    redwood = os.path.join(data, "rgbd_redwood")
    print("| policy | frames released / integrated / shown (after 1 s) | latency p50 / p99 (ms) "
          "| server's share p50 / p99 (ms) | runs |")
    print("|---|---|---:|---:|---|")
    for policy in ("realtime", "queue"):
        totals, servers, counts = [], [], []
        loops = 150 if policy == "realtime" else 30
        for _ in range(runs):
            p, url, log = start(["run", redwood, "--fuse", "--optimize", "none", "-o",
                                 os.path.join(work, "live"), "--json", "--serve", "0", "--rate",
                                 "30", "--loops", str(loops), "--policy", policy,
                                 "--exit-after", "120"])
            # The page completes once it has acknowledged the map's rounds (flow control:
            # serve/server.h) and has the end; then the server is stopped.
            d = page(url)
            doc = wait_json(p, log)
            p.terminate()
            p.wait()
            since = float(d["openedEpochMs"]) + 1000.0
            rows = [[float(x) for x in r.split(":")]
                    for r in d.get("mapLatencies", "").split(",") if r]
            steady = [(total, server) for _, entered, total, server in rows if entered >= since]
            totals += [t for t, _ in steady]
            servers += [s for _, s in steady]
            counts.append(f"{5 * loops} / {doc['frames_ok']} / {len(steady)}")
        print(f"| {policy} | {'; '.join(counts)} | {percentile(totals, 0.5):.0f} / "
              f"{percentile(totals, 0.99):.0f} | {percentile(servers, 0.5):.0f} / "
              f"{percentile(servers, 0.99):.0f} | {runs} |")
shutil.rmtree(work, ignore_errors=True)
