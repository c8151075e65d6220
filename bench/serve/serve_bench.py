#!/usr/bin/env python3
"""What watching costs and how fast a picture comes, measured on this machine (bench/RESULTS.md,
"Viewing"). Release build; kurt3d from MESHFLOW_DATA (default ../shared/data).

1. Time to the first picture and to the full mesh in headless Chromium for `meshflow view` of
   kurt3d scan000 meshed at 5 cm, at --serve-rate 10 and 100 Mbit/s (the page's own numbers from
   the WebSocket's opening), beside the time the same cap needs for the PLY file and for the
   single-rate .mfc (size x 8 / rate: nothing can be drawn before they are complete).
2. Frames/s of `meshflow run --synthetic-depth --triangulate rqt` (640 x 480) with 0, 1 and 4
   viewers that read everything (plain WebSocket clients: a handshake, then reading the socket).

usage: serve_bench.py BUILD_DIR [RUNS] [view,viewers]
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
parts = sys.argv[3] if len(sys.argv) > 3 else "view,viewers"  # which measurements
RATES = (10, 100)
here = os.path.dirname(os.path.abspath(__file__))
source = os.path.dirname(os.path.dirname(here))
meshflow = os.path.join(build, "meshflow")
data = os.environ.get("MESHFLOW_DATA", os.path.join(source, "..", "shared", "data"))
check = os.path.join(source, "tests", "serve", "browser_check.py")
chromium = shutil.which("chromium") or shutil.which("chromium-browser")
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


def viewer(url, stop):
    """A WebSocket client that completes the handshake and then reads everything."""
    host, port = url.split("//")[1].rstrip("/").split(":")
    s = socket.create_connection((host, int(port)))
    key = base64.b64encode(os.urandom(16)).decode()
    s.sendall((f"GET /ws HTTP/1.1\r\nHost: {host}\r\nUpgrade: websocket\r\n"
               f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
               "Sec-WebSocket-Version: 13\r\n\r\n").encode())
    s.settimeout(0.2)
    while not stop.is_set():
        try:
            if not s.recv(1 << 16):
                break
        except socket.timeout:
            pass
    s.close()


# 1. first picture / full mesh
if "view" not in parts:
    RATES = ()
scan = os.path.join(data, "kurt3d", "scan000.3d")
mesh = os.path.join(work, "kurt3d.ply")
subprocess.run([meshflow, "reconstruct", scan, "--voxel", "0.05", "-o", mesh], check=True,
               stdout=subprocess.DEVNULL)
mfc = os.path.join(work, "kurt3d.mfc")
subprocess.run([meshflow, "reconstruct", scan, "--voxel", "0.05", "-o", mfc], check=True,
               stdout=subprocess.DEVNULL)
ply_bytes, mfc_bytes = os.path.getsize(mesh), os.path.getsize(mfc)
print(f"kurt3d scan000 at 5 cm: PLY {ply_bytes} bytes, single-rate .mfc {mfc_bytes} bytes")
print("| cap | first picture (ms) | full mesh (ms) | progressive bytes | PLY at the cap | .mfc at the cap |")
print("|---:|---:|---:|---:|---:|---:|")
for rate in RATES:
    first, full = [], []
    for _ in range(runs):
        p, url, log = start(["view", mesh, "--serve", "0", "--serve-rate", str(rate),
                             "--chunk-kb", "16", "--exit-after", "120"])
        out = os.path.join(work, "page.json")
        subprocess.run([sys.executable, check, chromium, url, out, out + ".png", "60"],
                       check=True, stdout=subprocess.DEVNULL)
        d = json.load(open(out))
        first.append(float(d["firstMs"]))
        full.append(float(d["fullMs"]))
        p.terminate()
        p.wait()
        log.seek(0)
        stdout = log.read()
    progressive = int(re.search(r"(\d+) bytes progressive", stdout).group(1))
    print(f"| {rate} Mbit/s | {statistics.median(first):.0f} | {statistics.median(full):.0f} | "
          f"{progressive} | {ply_bytes * 8 / (rate * 1e3):.0f} ms | "
          f"{mfc_bytes * 8 / (rate * 1e3):.0f} ms |")

# 2. frames/s with 0, 1, 4 viewers
print("| viewers | frames/s (median of runs) | runs |")
print("|---:|---:|---|")
for viewers in (0, 1, 4) if "viewers" in parts else ():
    rates = []
    for _ in range(runs):
        p, url, log = start(["run", "--synthetic-depth", "--synthetic-frames", "120",
                             "--triangulate", "rqt", "-o", os.path.join(work, "run"), "--json",
                             "--serve", "0", "--exit-after", "0.01"])
        stop = threading.Event()
        threads = [threading.Thread(target=viewer, args=(url, stop)) for _ in range(viewers)]
        for t in threads:
            t.start()
        p.wait()
        log.seek(0)
        doc = json.loads(log.read())
        stop.set()
        for t in threads:
            t.join()
        rates.append(doc["frames_per_second"])
    print(f"| {viewers} | {statistics.median(rates):.1f} | "
          f"{', '.join(f'{r:.1f}' for r in rates)} |")
shutil.rmtree(work, ignore_errors=True)
