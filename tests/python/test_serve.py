"""meshflow.serve: a mesh shown in the browser from Python, fetched back over HTTP (urllib).

Fails (never skips) when the module was built without the serving layer."""
import os
import socket
import subprocess
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


@pytest.mark.parametrize("kwargs", [dict(port=65536), dict(port=-1), dict(host=""),
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
