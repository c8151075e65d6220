"""meshflow.serve and Pipeline(serve=...): meshes shown in the browser from Python, fetched
back over HTTP (urllib) and over the page's WebSocket (a minimal RFC 6455 reader below).

Fails (never skips) when the module was built without the serving layer."""
import base64
import json
import os
import socket
import struct
import subprocess
import threading
import urllib.error
import urllib.request

import numpy as np
import pytest

import meshflow

CLI = os.environ["MESHFLOW_CLI"]


def fetch(url):
    with urllib.request.urlopen(url, timeout=10) as response:
        return response.status, response.headers.get("Content-Type"), response.read()


@pytest.fixture(scope="module")
def room_ply(tmp_path_factory):
    path = str(tmp_path_factory.mktemp("room") / "room.ply")
    subprocess.run([CLI, "demo", "-o", path, "-q"], check=True)
    return path


def test_serves_the_page_and_the_mesh_of_a_file_on_the_loopback(room_ply):
    expected = meshflow.read_mesh(room_ply)
    with meshflow.serve(room_ply, port=0) as view:
        assert view.host == "127.0.0.1"  # safe by default
        assert view.port > 0
        assert view.url == "http://127.0.0.1:%d/" % view.port
        status, kind, page = fetch(view.url)
        assert status == 200 and kind.startswith("text/html")
        assert b"viewer.js" in page
        status, kind, wasm = fetch(view.url + "mfc_decoder.wasm")
        assert kind == "application/wasm" and wasm[:4] == b"\0asm"
        status, kind, mfc = fetch(view.url + "mesh.mfc")
        assert status == 200
        served = meshflow.decompress(mfc)
        assert len(served.triangles) == len(expected.triangles)
        assert len(served.vertices) == len(expected.vertices)
        # Within the codec's quantisation of the file's vertices (as sets: the codec reorders).
        extent = np.ptp(expected.vertices, axis=0).max()
        assert np.allclose(np.sort(served.vertices, axis=0), np.sort(expected.vertices, axis=0),
                           atol=1e-3 * extent)
        assert view.stats()["http_requests"] >= 3
        with pytest.raises(urllib.error.HTTPError) as missing:  # only its fixed files
            fetch(view.url + "etc/passwd")
        assert missing.value.code == 404
    assert not view.open
    with pytest.raises(OSError):  # closed: nothing listens any more
        socket.create_connection(("127.0.0.1", view.port), timeout=2).close()


def test_serves_a_mesh_object_and_its_counts():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float32)
    triangles = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], dtype=np.uint32)
    mesh = meshflow.Mesh(vertices, triangles)
    view = meshflow.serve(mesh, port=0, serve_rate=50, max_viewers=2)
    try:
        served = meshflow.decompress(fetch(view.url + "mesh.mfc")[2])
        assert len(served.triangles) == 4 and len(served.vertices) == 4
    finally:
        view.close()
    view.close()  # idempotent


@pytest.mark.parametrize("kwargs", [dict(port=65536), dict(port=-1), dict(port=10**30),
                                    dict(host=""),
                                    dict(host="not a host"), dict(host="[::1]")])
def test_a_bad_address_is_the_clis_message(room_ply, kwargs):
    with pytest.raises(ValueError, match=r"expected \[HOST:\]PORT"):
        meshflow.serve(room_ply, **kwargs)


def test_other_settings_are_checked_by_the_option_model(room_ply):
    with pytest.raises(ValueError, match=r"serve_rate: expected a number in \[0, "):
        meshflow.serve(room_ply, port=0, serve_rate=-1)
    with pytest.raises(ValueError, match=r"max_viewers: expected a number in \[1, 256\]"):
        meshflow.serve(room_ply, port=0, max_viewers=0)
    with pytest.raises(TypeError, match="port"):
        meshflow.serve(room_ply, port="8080")


def test_a_port_in_use_is_an_error_naming_the_address(room_ply):
    holder = socket.socket()
    holder.bind(("127.0.0.1", 0))
    holder.listen(1)
    try:
        port = holder.getsockname()[1]
        with pytest.raises(meshflow.Error, match="127.0.0.1:%d" % port):
            meshflow.serve(room_ply, port=port)
    finally:
        holder.close()


class Viewer(threading.Thread):
    """A WebSocket client of the page's /ws: keeps every message (text as JSON, binary as
    bytes) until the server's {"type": "end"} or a closed connection."""

    def __init__(self, url):
        super().__init__(daemon=True)
        host, port = url.split("//")[1].rstrip("/").split(":")
        self.sock = socket.create_connection((host, int(port)), timeout=30)
        key = base64.b64encode(os.urandom(16)).decode()
        self.sock.sendall((f"GET /ws HTTP/1.1\r\nHost: {host}\r\nUpgrade: websocket\r\n"
                           f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
                           "Sec-WebSocket-Version: 13\r\n\r\n").encode())
        reply = b""
        while b"\r\n\r\n" not in reply:
            reply += self.sock.recv(1)
        assert reply.startswith(b"HTTP/1.1 101"), reply
        self.texts, self.binaries, self.ended = [], [], threading.Event()

    def read(self, n):
        data = b""
        while len(data) < n:
            part = self.sock.recv(n - len(data))
            if not part:
                raise EOFError
            data += part
        return data

    def run(self):
        message, opcode = b"", 0
        try:
            while True:
                b0, b1 = self.read(2)
                length = b1 & 0x7F
                if length == 126:
                    length = struct.unpack(">H", self.read(2))[0]
                elif length == 127:
                    length = struct.unpack(">Q", self.read(8))[0]
                payload = self.read(length)  # frames from a server are never masked
                if b0 & 0x0F:
                    opcode = b0 & 0x0F
                message += payload
                if not b0 & 0x80:
                    continue
                if opcode == 1:
                    self.texts.append(json.loads(message))
                    if self.texts[-1].get("type") == "end":
                        break
                elif opcode == 2:
                    self.binaries.append(message)
                elif opcode == 8:
                    break
                message = b""
        except (EOFError, OSError):
            pass
        self.ended.set()


def sphere_points(n=6000, seed=0):
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n, 3))
    return (0.5 * p / np.linalg.norm(p, axis=1, keepdims=True)).astype(np.float32)


def test_a_pipeline_shows_its_meshes_while_they_are_made():
    meshes = []
    with meshflow.Pipeline(meshes.append, policy="offline", voxel=0.05, serve=0) as live:
        assert live.url.startswith("http://127.0.0.1:")  # safe by default
        status, kind, page = fetch(live.url)
        assert status == 200 and b"viewer.js" in page
        viewer = Viewer(live.url)
        viewer.start()
        for seed in range(4):
            live.push(sphere_points(seed=seed))
        live.flush()
    assert viewer.ended.wait(30), "no end message after close()"
    assert len(meshes) == 4 and all(r.ok for r in meshes)
    # A slow viewer's queue keeps only the newest stats: each one received names its frame.
    stats = [t for t in viewer.texts if t.get("type") == "stats" and "frame" in t]
    triangles = {r.seq: len(r.mesh.triangles) for r in meshes}
    assert stats and all(t["source"] == "meshflow.Pipeline" for t in stats)
    assert all(t["triangles"] == triangles[t["frame"]] for t in stats)
    assert viewer.texts[-1] == {"type": "end"}
    # The last mesh header and its chunks: u32 id, u32 offset, then the .mfc bytes.
    header = [t for t in viewer.texts if t.get("type") == "mesh"][-1]
    image = bytearray(header["bytes"])
    for chunk in viewer.binaries:
        mesh_id, offset = struct.unpack("<II", chunk[:8])
        if mesh_id == header["id"]:
            image[offset:offset + len(chunk) - 8] = chunk[8:]
    shown = meshflow.decompress(bytes(image))
    assert len(shown.triangles) == len(meshes[-1].mesh.triangles)
    assert live.url is not None
    with pytest.raises(OSError):  # closed: nothing listens any more
        socket.create_connection(("127.0.0.1", int(live.url.rsplit(":", 1)[1].rstrip("/"))),
                                 timeout=2).close()


def test_a_pipeline_without_serve_has_no_url():
    with meshflow.Pipeline(lambda r: None) as live:
        assert live.url is None


@pytest.mark.parametrize("serve", ["abc", "65536", 10**30, -1])
def test_a_pipelines_bad_address_is_the_clis_message(serve):
    with pytest.raises(ValueError, match=r"serve: expected \[HOST:\]PORT"):
        meshflow.Pipeline(lambda r: None, serve=serve)


def test_a_pipelines_serving_settings_are_checked():
    with pytest.raises(TypeError, match="serve"):
        meshflow.Pipeline(lambda r: None, serve=1.5)
    with pytest.raises(ValueError, match=r"max_viewers: expected a number in \[1, 256\]"):
        meshflow.Pipeline(lambda r: None, serve=0, max_viewers=10**30)
