"""Depth images, TSDF fusion, the embedding Pipeline and evaluate() from Python."""
import json
import os
import subprocess
import threading

import numpy as np
import pytest

import meshflow

CLI = os.environ["MESHFLOW_CLI"]
K = meshflow.Intrinsics(160, 120, 150.0, 150.0, 79.5, 59.5)
RADIUS = 0.3


def look_at(eye, target=(0.0, 0.0, 0.0)):
    """Camera-to-world pose of a camera at eye looking at target (x right, y down, z forward)."""
    eye = np.asarray(eye, dtype=np.float64)
    z = np.asarray(target) - eye
    z /= np.linalg.norm(z)
    x = np.cross(z, [0.0, 1.0, 0.0]) if abs(z[1]) < 0.9 else np.cross(z, [1.0, 0.0, 0.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = x, y, z, eye
    return pose


def sphere_depth(pose, dtype=np.float32):
    """Ray-cast depth (metres along z) of the sphere of RADIUS at the origin."""
    u, v = np.meshgrid(np.arange(K.width), np.arange(K.height))
    rays = np.stack([(u - K.cx) / K.fx, (v - K.cy) / K.fy, np.ones_like(u, dtype=float)], -1)
    d = rays @ pose[:3, :3].T  # world directions, z component 1 in the camera frame
    o = pose[:3, 3]
    a = (d * d).sum(-1)
    b = 2.0 * (d @ o)
    c = o @ o - RADIUS ** 2
    disc = b * b - 4 * a * c
    t = np.where(disc > 0, (-b - np.sqrt(np.maximum(disc, 0))) / (2 * a), 0.0)
    if dtype == np.uint16:
        return np.round(t * 1000).astype(np.uint16)
    return t.astype(dtype)


def test_triangulated_depth_lies_on_the_sphere():
    pose = look_at([0.0, 0.0, -1.2])
    for depth in (sphere_depth(pose), sphere_depth(pose, np.uint16)):
        for method in ("naive", "rqt"):
            mesh = meshflow.triangulate_depth(depth, K, pose, method=method)
            r = np.linalg.norm(mesh.vertices, axis=1)
            assert len(mesh.triangles) > 500, method
            assert np.abs(r - RADIUS).max() < 0.003, method
    color = np.zeros((K.height, K.width, 3), dtype=np.uint8)
    color[..., 1] = 180
    mesh = meshflow.triangulate_depth(sphere_depth(pose), K, pose, color=color, decimate=0.5)
    assert mesh.colors is not None and (mesh.colors[:, 1] == 180).all()
    assert mesh.normals is not None


def test_fused_views_close_around_the_sphere():
    volume = meshflow.TsdfVolume(voxel=0.01)
    for angle in np.linspace(0, 2 * np.pi, 8, endpoint=False):
        pose = look_at([1.0 * np.sin(angle), 0.2, -1.0 * np.cos(angle)])
        stats = volume.integrate(sphere_depth(pose), K, pose)
        assert stats["pixels_used"] > 1000
        assert stats["noise_per_depth2"] >= 0.0
    mesh = volume.extract()
    np.testing.assert_array_equal(volume.extract(incremental=False).triangles, mesh.triangles)
    r = np.linalg.norm(mesh.vertices, axis=1)
    assert volume.block_count > 0 and len(mesh.triangles) > 2000
    assert abs(r.mean() - RADIUS) < 0.002 and np.abs(r - RADIUS).max() < 0.01
    symmetric = meshflow.TsdfVolume(voxel=0.01, behind=4.0)  # Open3D's band: also closes
    for angle in np.linspace(0, 2 * np.pi, 8, endpoint=False):
        pose = look_at([1.0 * np.sin(angle), 0.2, -1.0 * np.cos(angle)])
        symmetric.integrate(sphere_depth(pose), K, pose)
    assert len(symmetric.extract().triangles) > 2000
    along = meshflow.TsdfVolume(voxel=0.01, integrator="along-ray")  # voxblox-style rays
    for angle in np.linspace(0, 2 * np.pi, 8, endpoint=False):
        pose = look_at([1.0 * np.sin(angle), 0.2, -1.0 * np.cos(angle)])
        along.integrate(sphere_depth(pose), K, pose)
    r = np.linalg.norm(along.extract().vertices, axis=1)
    assert len(r) > 1000 and abs(r.mean() - RADIUS) < 0.002 and np.abs(r - RADIUS).max() < 0.01
    with pytest.raises(meshflow.Error, match="behind_voxels"):
        meshflow.TsdfVolume(voxel=0.01, behind=0.0)
    with pytest.raises(meshflow.Error, match="integrator"):
        meshflow.TsdfVolume(integrator="raycast")


def test_surface_seen_through_later_is_carved():
    wall = np.full((K.height, K.width), 3.0, dtype=np.float32)
    passer_by = wall.copy()  # something 1.5 m away in the first frame only
    passer_by[K.height // 3 : 2 * K.height // 3, K.width // 3 : 2 * K.width // 3] = 1.5
    for carve in (True, False):
        volume = meshflow.TsdfVolume(voxel=0.03, carve=carve)
        volume.integrate(passer_by, K)
        carved = volume.integrate(wall, K)["blocks_carved"]
        in_front = int((volume.extract().vertices[:, 2] < 2.5).sum())
        if carve:
            assert carved > 0 and in_front == 0
        else:
            assert carved == 0 and in_front > 100


def test_bad_depth_input_is_a_clear_error():
    pose = look_at([0.0, 0.0, -1.2])
    depth = sphere_depth(pose)
    with pytest.raises(ValueError, match="depth: expected a \\(height, width\\) array"):
        meshflow.triangulate_depth(depth[0], K, pose)
    with pytest.raises(ValueError, match="pose: expected a 4 x 4"):
        meshflow.triangulate_depth(depth, K, np.eye(3))
    with pytest.raises(meshflow.Error, match="triangulate: no triangle"):  # not an empty Mesh
        meshflow.triangulate_depth(np.zeros_like(depth), K, pose)
    bad_pose = pose.copy()
    bad_pose[0, 3] = np.nan
    with pytest.raises(ValueError, match="pose: not finite"):
        meshflow.TsdfVolume().integrate(depth, K, bad_pose)
    with pytest.raises(meshflow.Error):  # the image does not match the intrinsics
        meshflow.triangulate_depth(depth[:, :100], K, pose)
    with pytest.raises(ValueError, match="method"):
        meshflow.triangulate_depth(depth, K, pose, method="delaunay")


def sphere_cloud(seed, n=8000):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return meshflow.Cloud((RADIUS * v).astype(np.float32), v.astype(np.float32))


def test_pipeline_calls_back_in_push_order_with_exact_accounting():
    results = []
    caller = threading.get_ident()
    threads = set()

    def on_mesh(result):
        threads.add(threading.get_ident())
        results.append(result)

    with meshflow.Pipeline(on_mesh, policy="queue", max_waiting=16, voxel=0.04) as live:
        pushed = [live.push(sphere_cloud(i)) for i in range(6)]
        pushed.append(live.push(np.zeros((0, 3), dtype=np.float32)))  # fails: no points
        pushed.append(live.push_depth(sphere_depth(look_at([0, 0, -1.2])), K,
                                      look_at([0, 0, -1.2])))
        live.flush()
        stats = live.stats()
    assert [p[1] for p in pushed] == ["accepted"] * 8
    assert [r.seq for r in results] == [p[0] for p in pushed]
    assert all(r.ok for r in results[:6]) and results[7].ok
    assert not results[6].ok and results[6].mesh is None and results[6].error
    for r in results[:6]:
        radii = np.linalg.norm(r.mesh.vertices, axis=1)
        assert abs(radii.mean() - RADIUS) < 0.01
    assert stats["pushed"] == 8 and stats["delivered"] == 8 and stats["failed"] == 1
    assert caller not in threads  # called back on the pipeline's threads


def test_a_degenerate_cloud_is_a_failed_frame_not_an_empty_mesh():
    """Three points: reconstruct() raises, and Pipeline delivers a failed frame saying why."""
    three = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float32)
    with pytest.raises(meshflow.Error, match="no surface|triangles") as raised:
        meshflow.reconstruct(three)
    message = str(raised.value)
    assert message.count(": extract:") + message.count(": optimize:") == 1, message  # once
    results = []
    with meshflow.Pipeline(results.append, policy="queue") as live:
        live.push(three)
        live.flush()
        stats = live.stats()
    assert len(results) == 1
    assert not results[0].ok and results[0].mesh is None
    assert results[0].failed_stage in ("extract", "optimize")
    assert "triangle" in results[0].error
    assert stats["delivered"] == 1 and stats["failed"] == 1


# The callback's exception is printed as Python prints one raised in a thread (pytest turns
# that into a warning).
@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_pipeline_counts_callback_exceptions_and_keeps_going():
    seen = []

    def on_mesh(result):
        seen.append(result.seq)
        if result.seq == 0:
            raise RuntimeError("deliberate")

    live = meshflow.Pipeline(on_mesh, policy="queue", voxel=0.04)
    live.push(sphere_cloud(1))
    live.push(sphere_cloud(2))
    live.flush()
    assert seen == [0, 1] and live.stats()["callback_exceptions"] == 1
    live.close()
    with pytest.raises(meshflow.Error, match="closed"):
        live.push(sphere_cloud(3))


def test_evaluate_gives_the_cli_figures(tmp_path):
    cloud = sphere_cloud(5, 20000)
    mesh = meshflow.reconstruct(cloud, voxel=0.02)
    figures = meshflow.evaluate(mesh, cloud)
    # To the nearest of 20 000 points 7.5 mm apart: a few millimetres.
    assert figures["mesh_to_reference"]["mean"] < 0.005
    assert figures["reference_to_mesh"]["mean"] < 0.001
    assert figures["topology"]["watertight"] and figures["orientation"] == "outward"
    mesh_path, points_path = str(tmp_path / "m.ply"), str(tmp_path / "p.ply")
    mesh.write(mesh_path)
    subprocess.run([CLI, "sample", "sphere", "--points", "5000", "-o", points_path, "-q"],
                   check=True)
    from_cli = json.loads(subprocess.run([CLI, "eval", mesh_path, "--reference", points_path,
                                          "--json"], check=True, capture_output=True,
                                         text=True).stdout)
    from_python = meshflow.evaluate(meshflow.read_mesh(mesh_path), points_path)
    for key in ("mesh_to_reference", "reference_to_mesh", "topology", "double_walls",
                "normal_deviation_deg", "orientation"):
        assert from_python[key] == from_cli[key], key
