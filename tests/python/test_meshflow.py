"""The Python module against the CLI and analytic shapes (run by ctest as Python.pytest)."""
import math
import os
import subprocess
import threading

import numpy as np
import pytest

import meshflow

CLI = os.environ["MESHFLOW_CLI"]
DATA = os.environ.get("MESHFLOW_DATA", os.path.join(os.environ["MESHFLOW_SOURCE_DIR"], "..",
                                                    "shared", "data"))


def cli(*args):
    subprocess.run([CLI, *args, "-q"], check=True)


@pytest.fixture(scope="module")
def torus_ply(tmp_path_factory):
    path = str(tmp_path_factory.mktemp("torus") / "torus.ply")
    cli("sample", "torus", "--points", "60000", "-o", path)
    return path


def sphere_points(n=40000, radius=0.5, seed=3):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return (radius * v).astype(np.float32), v.astype(np.float32)


def test_same_triangles_as_the_cli(torus_ply, tmp_path):
    out = str(tmp_path / "cli.ply")
    cli("reconstruct", torus_ply, "--voxel", "0.02", "-o", out)
    expected = meshflow.read_mesh(out)
    mesh = meshflow.reconstruct(meshflow.read_cloud(torus_ply), voxel=0.02)
    np.testing.assert_array_equal(mesh.triangles, expected.triangles)
    np.testing.assert_array_equal(mesh.vertices, expected.vertices)


@pytest.mark.skipif(not os.path.exists(os.path.join(DATA, "kurt3d", "scan000.3d")),
                    reason="shared data absent (set MESHFLOW_DATA)")
def test_same_triangles_as_the_cli_on_a_laser_scan(tmp_path):
    scan = os.path.join(DATA, "kurt3d", "scan000.3d")
    out = str(tmp_path / "cli.ply")
    cli("reconstruct", scan, "--voxel", "0.05", "-o", out)
    mesh = meshflow.reconstruct(meshflow.read_cloud(scan), voxel=0.05)
    np.testing.assert_array_equal(mesh.triangles, meshflow.read_mesh(out).triangles)


def test_arrays_in_sphere_out():
    points, normals = sphere_points()
    mesh = meshflow.reconstruct(points, normals, voxel=0.02)
    radii = np.linalg.norm(mesh.vertices, axis=1)
    assert mesh.triangles.shape[1] == 3 and len(mesh.triangles) > 1000
    assert abs(radii.mean() - 0.5) < 0.002 and radii.std() < 0.003
    assert mesh.triangles.max() < len(mesh.vertices)
    # Without normals the orientation comes from propagation; still the same sphere.
    unoriented = meshflow.reconstruct(points.astype(np.float64), voxel=0.02)
    assert abs(np.linalg.norm(unoriented.vertices, axis=1).mean() - 0.5) < 0.002


def test_colours_reach_the_mesh():
    points, normals = sphere_points(20000)
    colors = np.where(points[:, 2:3] > 0, [255, 0, 0], [0, 0, 255]).astype(np.uint8)
    mesh = meshflow.reconstruct(points, normals, colors, voxel=0.04)
    assert mesh.colors is not None and mesh.colors.shape == mesh.vertices.shape
    assert mesh.normals is not None
    np.testing.assert_array_equal(mesh.colors[mesh.vertices[:, 2] > 0.1], [[255, 0, 0]] *
                                  int((mesh.vertices[:, 2] > 0.1).sum()))
    np.testing.assert_array_equal(mesh.colors[mesh.vertices[:, 2] < -0.1], [[0, 0, 255]] *
                                  int((mesh.vertices[:, 2] < -0.1).sum()))


def test_arrays_out_are_views_not_copies():
    points, normals = sphere_points(20000)
    mesh = meshflow.reconstruct(points, normals, voxel=0.04)
    v = mesh.vertices
    assert v.base is mesh and mesh.triangles.base is mesh
    assert v.dtype == np.float32 and v.flags.c_contiguous
    assert mesh.vertices.__array_interface__["data"][0] == v.__array_interface__["data"][0]
    v[0, 0] = 7.0  # writes through to the mesh
    assert mesh.vertices[0, 0] == 7.0
    cloud = meshflow.Cloud(points, normals)
    assert cloud.points.base is cloud and len(cloud) == len(points)
    np.testing.assert_array_equal(cloud.points, points)
    del mesh, cloud  # views keep their owners alive
    assert v[0, 0] == 7.0


def test_the_gil_is_released_while_reconstructing():
    points, normals = sphere_points(150000)
    ticks = 0
    done = threading.Event()

    def count():
        nonlocal ticks
        while not done.is_set():
            ticks += 1

    t = threading.Thread(target=count)
    t.start()
    try:
        before = ticks
        meshflow.reconstruct(points, normals, voxel=0.01, threads=1)
        during = ticks - before
    finally:
        done.set()
        t.join()
    assert during > 1000  # the counting thread ran while C++ worked


def test_write_round_trip(tmp_path):
    points, normals = sphere_points(20000)
    mesh = meshflow.reconstruct(points, normals, voxel=0.04)
    for ext in ("ply", "obj", "off", "stl"):
        path = str(tmp_path / f"sphere.{ext}")
        mesh.write(path)
        back = meshflow.read_mesh(path)
        assert len(back.triangles) == len(mesh.triangles), ext


def test_bad_arrays_are_value_errors():
    points, normals = sphere_points(1000)
    with pytest.raises(ValueError, match=r"points: expected shape \(n, 3\), got \(1000, 2\)"):
        meshflow.reconstruct(points[:, :2])
    with pytest.raises(ValueError, match="points: expected shape"):
        meshflow.reconstruct(points.ravel())
    bad = points.copy()
    bad[17, 1] = np.nan
    with pytest.raises(ValueError, match="points: row 17 is not finite"):
        meshflow.reconstruct(bad)
    with pytest.raises(ValueError, match="normals: 999 rows for 1000 points"):
        meshflow.reconstruct(points, normals[:999])
    with pytest.raises(ValueError, match="expected an array of numbers"):
        meshflow.reconstruct([["a", "b", "c"]])
    with pytest.raises(ValueError, match="orient"):
        meshflow.reconstruct(points, orient="sideways")
    with pytest.raises(ValueError, match="extract"):
        meshflow.reconstruct(points, extract="nonsense")
    with pytest.raises(ValueError, match=r"colors: expected integers 0-255 \(uint8\), got float64"):
        meshflow.Cloud(points, colors=np.full((1000, 3), 0.5))
    over = np.full((1000, 3), 200, dtype=np.int64)
    over[3, 2] = 256
    with pytest.raises(ValueError, match="colors: row 3 has a value outside 0-255"):
        meshflow.Cloud(points, colors=over)
    colored = meshflow.Cloud(points, colors=np.full((1000, 3), 200, dtype=np.int64))
    assert colored.colors.dtype == np.uint8 and colored.colors[5, 1] == 200
    # Strided input is fine: it is copied.
    wide = np.zeros((1000, 6), dtype=np.float64)
    wide[:, ::2] = points
    assert meshflow.Cloud(wide[:, ::2]).points.shape == (1000, 3)


def test_every_cli_option_is_a_keyword():
    points, normals = sphere_points(20000)
    # Exact samples with exact normals get extended marching cubes, which places vertices from
    # the points themselves; marching cubes shows the distance settings.
    base = meshflow.reconstruct(points, normals, voxel=0.04, extract="mc")
    # Options the CLI has, by the CLI's names: kd = 1 averages fewer tangent planes, another mesh.
    other = meshflow.reconstruct(points, normals, voxel=0.04, extract="mc", kd=1, max_distance=3.0,
                                 min_component=10, optimize="clean", orient="input")
    assert not np.array_equal(base.vertices, other.vertices) or len(base.vertices) != len(
        other.vertices)
    with pytest.raises(TypeError, match="unexpected keyword argument 'voxle'.*voxel=0.0"):
        meshflow.reconstruct(points, voxle=0.04)
    with pytest.raises(TypeError, match="kn: expected a value like 10"):
        meshflow.reconstruct(points, kn="ten")
    assert "max_extrapolation=" in meshflow.reconstruct.__doc__


def test_values_the_cli_refuses_python_refuses_with_the_same_message():
    # Issue 55: these were accepted (max_distance=-1 returned 56 triangles).
    points, _ = sphere_points(2000)
    cases = {
        "voxel": (-5, r"voxel: expected a number in \[0, 1000\], got -5"),
        "kn": (-3, r"kn: expected a number in \[3, 1000\], got -3"),
        "decimate_to": (5, r"decimate_to: expected a number in \[0, 1\], got 5"),
        "max_distance": (-1, r"max_distance: expected a number in \(0, 1000\], got -1"),
        "min_component": (-2, r"min_component: expected a whole number >= 0, got -2"),
        "depth_median": (4, r"depth_median: expected one of 0, 3, 5; got 4"),
    }
    for name, (value, message) in cases.items():
        with pytest.raises(ValueError, match=message):
            meshflow.reconstruct(points, **{name: value})
        with pytest.raises(ValueError, match=message):
            meshflow.Pipeline(lambda result: None, **{name: value})
    with pytest.raises(ValueError, match=r"voxel: expected a number in \[0, 1000\], got nan"):
        meshflow.reconstruct(points, voxel=float("nan"))
    with pytest.raises(TypeError, match="adaptive_k: expected a value like False"):
        meshflow.reconstruct(points, adaptive_k=1)


def test_meshflow_errors_name_the_file(tmp_path):
    missing = str(tmp_path / "missing.ply")
    with pytest.raises(meshflow.Error, match="missing.ply"):
        meshflow.read_cloud(missing)
    broken = tmp_path / "broken.ply"
    broken.write_text("ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nend_header\n1\n")
    with pytest.raises(meshflow.Error, match="broken.ply"):
        meshflow.read_cloud(str(broken))
    with pytest.raises(meshflow.Error):
        meshflow.reconstruct(np.zeros((0, 3), dtype=np.float32))
    assert issubclass(meshflow.Error, RuntimeError)
    assert meshflow.__version__


def test_compress_round_trip_and_levels(torus_ply):
    mesh = meshflow.reconstruct(meshflow.read_cloud(torus_ply), voxel=0.02)
    data = meshflow.compress(mesh)
    assert isinstance(data, bytes)
    assert 8 * len(data) / len(mesh.triangles) < 32
    back = meshflow.decompress(data)
    assert len(back.triangles) == len(mesh.triangles)
    assert len(back.vertices) == len(mesh.vertices)
    # Vertices come back reordered, each within half a quantisation step (1/64 of the median
    # edge): the bounds and the centroid agree to that.
    step = np.median(np.linalg.norm(mesh.vertices[mesh.triangles[:, 0]] -
                                    mesh.vertices[mesh.triangles[:, 1]], axis=1)) / 64
    for reduce in (np.min, np.max, np.mean):
        assert np.abs(reduce(mesh.vertices, axis=0) - reduce(back.vertices, axis=0)).max() < step
    stream = meshflow.compress(mesh, progressive=True)
    coarse = meshflow.decompress(stream, splits=0)
    assert 0 < len(coarse.triangles) < len(mesh.triangles) / 10
    half = meshflow.decompress(stream, triangles=len(mesh.triangles) // 2)
    assert abs(len(half.triangles) - len(mesh.triangles) // 2) <= 4
    with pytest.raises(meshflow.Error, match="checksum"):
        meshflow.decompress(data[:-9] + bytes([data[-9] ^ 1]) + data[-8:])


def test_a_mesh_from_arrays_writes_and_reads_back(tmp_path):
    # Issue 55: an Open3D mesh (np.asarray(mesh.vertices), np.asarray(mesh.triangles)) comes in
    # without a file.
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
    triangles = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], dtype=np.int32)
    colors = np.array([[255, 0, 0], [0, 255, 0], [0, 0, 255], [9, 9, 9]], dtype=np.uint8)
    mesh = meshflow.Mesh(vertices, triangles, colors=colors)
    assert mesh.vertices.shape == (4, 3) and mesh.triangles.shape == (4, 3)
    assert mesh.normals is None and mesh.colors[3, 0] == 9
    path = str(tmp_path / "tet.ply")
    mesh.write(path)
    back = meshflow.read_mesh(path)
    assert np.array_equal(back.triangles, mesh.triangles)
    with pytest.raises(ValueError, match="triangles: row 1 refers to vertex 4 of 4"):
        meshflow.Mesh(vertices, np.array([[0, 1, 2], [1, 2, 4]]))
    with pytest.raises(ValueError, match="triangles: row 0 refers to vertex -1 of 4"):
        meshflow.Mesh(vertices, np.array([[0, 1, -1]]))
    with pytest.raises(ValueError, match="normals: 3 rows for 4 vertices"):
        meshflow.Mesh(vertices, triangles, normals=vertices[:3])
    bad = vertices.copy()
    bad[2, 0] = np.inf
    with pytest.raises(ValueError, match="vertices: row 2 is not finite"):
        meshflow.Mesh(bad, triangles)


def border_edge_count(triangles):
    """Edges used by one triangle only."""
    edges = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]],
                                    triangles[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return int((counts == 1).sum())


def test_close_and_outlier_removal_are_keywords():
    # A sphere without its top cap (unseen), plus isolated points far from it.
    points, normals = sphere_points(30000)
    keep = points[:, 2] < 0.3
    strays = np.array([[0.9, 0.9, 0.9], [-0.9, 0.9, -0.9], [0.9, -0.9, 0.0]], np.float32)
    cloud = np.concatenate([points[keep], strays])
    open_mesh = meshflow.reconstruct(cloud, voxel=0.02)
    assert border_edge_count(open_mesh.triangles) > 0
    assert np.linalg.norm(open_mesh.vertices, axis=1).max() < 0.55  # the strays are gone
    closed = meshflow.reconstruct(cloud, voxel=0.02, close=True)
    assert border_edge_count(closed.triangles) == 0
    assert closed.vertices[:, 2].max() > 0.3  # the cap's opening is spanned
    off = meshflow.reconstruct(cloud, voxel=0.02, outlier_cluster=0, outlier_radius=3.0)
    assert len(off.triangles) > 1000
    with pytest.raises(ValueError, match="outlier_radius"):
        meshflow.reconstruct(cloud, outlier_radius=0.0)
