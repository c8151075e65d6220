#!/usr/bin/env python3
"""Loads a page in headless Chromium and waits until it says it is done, then writes its body's
data attributes (JSON) and a screenshot (PNG).

It drives Chromium through the DevTools protocol over --remote-debugging-pipe (JSON messages
ending in a NUL byte on file descriptors 3 and 4: no socket, no extra package), so it waits for
the page's own state instead of guessing a time: `--dump-dom` dumps at the load event, before a
WebSocket stream has arrived, and `--virtual-time-budget` runs ahead of real network messages.

usage: browser_check.py CHROMIUM URL OUT_JSON OUT_PNG [TIMEOUT_S]
Exit 0 when document.body.dataset.state became "complete" or "error" (the caller checks which),
1 on a timeout or a browser failure.
"""
import base64
import json
import os
import select
import shutil
import subprocess
import sys
import tempfile
import time

chromium, url, out_json, out_png = sys.argv[1:5]
timeout_s = float(sys.argv[5]) if len(sys.argv) > 5 else 60.0

to_browser_r, to_browser_w = os.pipe()
from_browser_r, from_browser_w = os.pipe()
profile = tempfile.mkdtemp(prefix="meshflow-chromium-")
flags = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run",
         "--disable-default-apps", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
         "--window-size=800,600", "--user-data-dir=" + profile, "--remote-debugging-pipe",
         "about:blank"]


def child_fds():
    # Through fresh copies: a pipe end may already be 3 or 4 (then dup2 to itself would keep
    # its close-on-exec flag).
    read_end, write_end = os.dup(to_browser_r), os.dup(from_browser_w)
    os.dup2(read_end, 3)
    os.dup2(write_end, 4)
    os.set_inheritable(3, True)
    os.set_inheritable(4, True)


log = open(out_json + ".chromium.log", "wb")
# The pipes are not inherited (Python opens them close-on-exec); their dup2 copies 3 and 4 are.
browser = subprocess.Popen([chromium] + flags, stdout=log, stderr=log, preexec_fn=child_fds,
                           close_fds=False)
os.close(to_browser_r)
os.close(from_browser_w)
buffer = b""
next_id = 0
deadline = time.monotonic() + timeout_s


def send(method, params=None, session=None):
    global next_id
    next_id += 1
    message = {"id": next_id, "method": method, "params": params or {}}
    if session:
        message["sessionId"] = session
    os.write(to_browser_w, json.dumps(message).encode() + b"\0")
    return next_id


def reply(wanted):
    global buffer
    while True:
        while b"\0" in buffer:
            raw, buffer = buffer.split(b"\0", 1)
            message = json.loads(raw)
            if message.get("id") == wanted:
                if "error" in message:
                    raise RuntimeError(f"DevTools error: {message['error']}")
                return message["result"]
        left = deadline - time.monotonic()
        if left <= 0 or not select.select([from_browser_r], [], [], left)[0]:
            raise TimeoutError("no answer from Chromium in time")
        chunk = os.read(from_browser_r, 1 << 20)
        if not chunk:
            raise RuntimeError("Chromium closed the pipe (see " + out_json + ".chromium.log)")
        buffer += chunk


def call(method, params=None, session=None):
    return reply(send(method, params, session))


status = 1
try:
    target = call("Target.createTarget", {"url": url})["targetId"]
    session = call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
    dataset = {}
    while time.monotonic() < deadline:
        result = call("Runtime.evaluate",
                      {"expression": "JSON.stringify(document.body ? document.body.dataset : {})",
                       "returnByValue": True}, session)
        dataset = json.loads(result["result"].get("value") or "{}")
        if dataset.get("state") in ("complete", "error"):
            break
        time.sleep(0.2)
    with open(out_json, "w") as f:
        json.dump(dataset, f)
    print("page:", json.dumps(dataset))
    if dataset.get("state") in ("complete", "error"):
        time.sleep(0.3)  # one more frame drawn
        shot = call("Page.captureScreenshot", {"format": "png"}, session)
        with open(out_png, "wb") as f:
            f.write(base64.b64decode(shot["data"]))
        status = 0
    else:
        print(f"FAIL: the page did not finish in {timeout_s:.0f} s", file=sys.stderr)
    try:
        send("Browser.close")
    except OSError:
        pass
except (RuntimeError, TimeoutError, OSError) as e:
    print("FAIL:", e, file=sys.stderr)
finally:
    try:
        browser.wait(timeout=10)
    except subprocess.TimeoutExpired:
        browser.kill()
        browser.wait()
    shutil.rmtree(profile, ignore_errors=True)
sys.exit(status)
