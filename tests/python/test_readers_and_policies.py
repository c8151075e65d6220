"""Issue 55 item 5: Pipeline's policies as a script sees them (a warning for each frame dropped
or refused, an 'offline' policy that drops none), the readers of depth images, trajectories
and meshflow's own .glb, and crop= from Python."""
import os
import subprocess
import warnings

import numpy as np
import pytest

import meshflow

CLI = os.environ["MESHFLOW_CLI"]


def sphere_cloud(seed, n=20000, radius=0.3):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return meshflow.Cloud((radius * v).astype(np.float32), v.astype(np.float32))


def test_realtime_policy_warns_when_a_script_loses_a_frame():
    clouds = [sphere_cloud(i) for i in range(6)]
    with pytest.warns(meshflow.FrameDroppedWarning, match="dropped.*policy='offline'"):
        with meshflow.Pipeline(lambda r: None, frames_in_flight=1, max_waiting=1,
                               voxel=0.02) as live:
            statuses = [live.push(c)[1] for c in clouds]  # a loop faster than reconstruction
            live.flush()
            stats = live.stats()
    assert "dropped_oldest" in statuses
    assert stats["dropped"] == statuses.count("dropped_oldest")
    assert issubclass(meshflow.FrameDroppedWarning, RuntimeWarning)


def test_queue_policy_warns_when_it_refuses_a_frame():
    with pytest.warns(meshflow.FrameDroppedWarning, match="refused"):
        with meshflow.Pipeline(lambda r: None, policy="queue", frames_in_flight=1,
                               max_waiting=1, voxel=0.02) as live:
            statuses = [live.push(sphere_cloud(i))[1] for i in range(6)]
            live.flush()
    assert "rejected" in statuses


def test_offline_policy_delivers_every_frame_without_a_warning():
    results = []
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a FrameDroppedWarning would fail the test
        with meshflow.Pipeline(results.append, policy="offline", frames_in_flight=1,
                               max_waiting=1, voxel=0.02) as live:
            statuses = [live.push(sphere_cloud(i))[1] for i in range(6)]
            live.flush()
            stats = live.stats()
    assert statuses == ["accepted"] * 6
    assert [r.seq for r in results] == list(range(6)) and all(r.ok for r in results)
    assert stats["dropped"] == 0 and stats["rejected"] == 0 and stats["delivered"] == 6
    with pytest.raises(ValueError, match="'realtime', 'queue' or 'offline'"):
        meshflow.Pipeline(lambda r: None, policy="drop-nothing")


def test_glb_written_by_meshflow_reads_back(tmp_path):
    mesh = meshflow.reconstruct(sphere_cloud(1), voxel=0.03)
    path = str(tmp_path / "m.glb")
    mesh.write(path)
    back = meshflow.read_mesh(path)
    assert np.array_equal(back.vertices, mesh.vertices)
    assert np.array_equal(back.triangles, mesh.triangles)
    assert back.normals is not None
    assert np.allclose(np.linalg.norm(back.normals, axis=1), 1.0, atol=1e-5)


def test_depth_images_and_trajectories_read_as_the_cli_reads_them(tmp_path):
    orbit = str(tmp_path / "orbit")
    subprocess.run([CLI, "sample", "sphere", "--orbit", "3", "--size", "160x120", "-o", orbit,
                    "-q"], check=True)
    k = meshflow.read_intrinsics(os.path.join(orbit, "camera.json"))
    assert (k.width, k.height) == (160, 120)
    times, poses = meshflow.read_trajectory(os.path.join(orbit, "groundtruth.txt"))
    assert poses.shape == (3, 4, 4) and times.shape == (3,)
    assert np.all(np.diff(times) > 0)
    rotations = poses[:, :3, :3]
    assert np.allclose(rotations @ rotations.transpose(0, 2, 1), np.eye(3), atol=1e-5)
    depth = meshflow.read_depth(os.path.join(orbit, "depth", "000000.png"))
    assert depth.dtype == np.uint16 and depth.shape == (120, 160)
    assert (depth > 0).sum() > 1000
    color = meshflow.read_color(os.path.join(orbit, "rgb", "000000.png"))
    assert color.dtype == np.uint8 and color.shape == (120, 160, 3)
    # The frame, at its pose, lies on the object: the sphere of radius 0.5 m that `sample
    # sphere` draws points from (its centre: the mean of many uniform points).
    points = str(tmp_path / "s.ply")
    subprocess.run([CLI, "sample", "sphere", "--points", "20000", "-o", points, "-q"], check=True)
    centre = np.asarray(meshflow.read_cloud(points).points).mean(axis=0)
    mesh = meshflow.triangulate_depth(depth, k, poses[0], depth_scale=5000.0)
    radii = np.linalg.norm(mesh.vertices - centre, axis=1)
    assert len(mesh.triangles) > 1000
    assert np.abs(radii - 0.5).max() < 0.02
    # The same poses written as a Redwood .log read back the same.
    log = tmp_path / "trajectory.log"
    log.write_text("".join(f"{i} {i} {i + 1}\n" + "\n".join(" ".join(f"{v:.9g}" for v in row)
                                                            for row in pose) + "\n"
                           for i, pose in enumerate(poses)))
    log_times, log_poses = meshflow.read_trajectory(str(log))
    assert np.array_equal(log_times, [0.0, 1.0, 2.0])
    assert np.allclose(log_poses, poses, atol=1e-6)
    with pytest.raises(meshflow.Error, match="000009.png"):
        meshflow.read_depth(os.path.join(orbit, "depth", "000009.png"))
    with pytest.raises(meshflow.Error, match="trajectory.log"):
        log.write_text("0 0 1\n1 0 0\n")
        meshflow.read_trajectory(str(log))


def test_crop_from_python_as_numbers_or_text():
    cloud = sphere_cloud(2)
    whole = meshflow.reconstruct(cloud, voxel=0.03)
    cap = meshflow.reconstruct(cloud, voxel=0.03, crop=(-1, -1, 0.1, 1, 1, 1))
    assert whole.vertices[:, 2].min() < -0.25
    assert cap.vertices[:, 2].min() > 0.1 - 0.06
    same = meshflow.reconstruct(cloud, voxel=0.03, crop="-1,-1,0.1,1,1,1")
    assert np.array_equal(same.vertices, cap.vertices)
    with pytest.raises(ValueError, match="crop: minz must be below maxz"):
        meshflow.reconstruct(cloud, crop=(0, 0, 1, 1, 1, 0))
    with pytest.raises(ValueError, match="crop: expected six numbers"):
        meshflow.reconstruct(cloud, crop=(0, 0, 1))
    with pytest.raises(TypeError, match="crop"):
        meshflow.reconstruct(cloud, crop=(0, 0, "a", 1, 1, 1))


def test_vertex_quality_is_the_distance_to_the_nearest_point(tmp_path):
    cloud = sphere_cloud(3, 5000)
    mesh = meshflow.reconstruct(cloud, voxel=0.03)
    quality = meshflow.vertex_quality(mesh, cloud)
    assert quality.dtype == np.float32 and quality.shape == (len(mesh.vertices),)
    points = np.asarray(cloud.points)
    for i in range(0, len(mesh.vertices), 97):  # brute force
        nearest = np.linalg.norm(points - mesh.vertices[i], axis=1).min()
        assert abs(quality[i] - nearest) < 1e-6
    assert np.array_equal(meshflow.vertex_quality(mesh, points), quality)  # arrays too
    path = str(tmp_path / "q.ply")
    mesh.write(path, quality=quality)
    header = open(path, "rb").read(400).split(b"end_header")[0]
    assert b"property float quality" in header
    assert len(meshflow.read_mesh(path).vertices) == len(mesh.vertices)
    with pytest.raises(ValueError, match="one number per vertex"):
        mesh.write(path, quality=quality[:-1])
    with pytest.raises(ValueError, match=r"\.ply"):
        mesh.write(str(tmp_path / "q.obj"), quality=quality)


def test_vertex_observations_count_the_points_within_the_radius(tmp_path):
    cloud = sphere_cloud(3, 5000)
    mesh = meshflow.reconstruct(cloud, voxel=0.03)
    observations = meshflow.vertex_observations(mesh, cloud, 0.03)
    assert observations.dtype == np.float32 and observations.shape == (len(mesh.vertices),)
    points = np.asarray(cloud.points)
    for i in range(0, len(mesh.vertices), 97):  # brute force
        within = (np.linalg.norm(points - mesh.vertices[i], axis=1) <= 0.03).sum()
        assert abs(observations[i] - within) <= 1  # rounding at the radius
    assert observations.min() >= 1
    path = str(tmp_path / "o.ply")
    quality = meshflow.vertex_quality(mesh, cloud)
    mesh.write(path, quality=quality, observations=observations)
    header = open(path, "rb").read(500).split(b"end_header")[0]
    assert b"property float quality\nproperty float observations" in header
    with pytest.raises(meshflow.Error, match="positive radius"):
        meshflow.vertex_observations(mesh, cloud, 0.0)


@pytest.mark.filterwarnings("ignore::meshflow.FrameDroppedWarning")
def test_offline_callback_may_push_without_waiting_for_itself():
    """A callback that pushes into an offline pipeline does not wait for room (its own thread
    makes the room): no deadlock, every push accounted for."""
    results = []

    def on_mesh(result):
        results.append(result.seq)
        if result.seq < 2:
            live.push(sphere_cloud(10 + result.seq))

    live = meshflow.Pipeline(on_mesh, policy="offline", frames_in_flight=1, max_waiting=1,
                             voxel=0.03)
    for i in range(3):
        live.push(sphere_cloud(i))
    live.flush()
    stats = live.stats()
    live.close()
    assert stats["pushed"] == 5
    assert stats["delivered"] + stats["rejected"] == 5 and stats["dropped"] == 0
    assert results == sorted(results)


def test_vertex_quality_compares_georeferenced_mesh_and_cloud_in_one_frame(tmp_path):
    """A terrain tile in map coordinates is read in a local frame; its mesh written and read
    back is in world coordinates: the distances are the same either way."""
    x, y = np.meshgrid(np.arange(0, 20, 0.4), np.arange(0, 20, 0.4))
    z = 300 + np.sin(0.3 * x) * np.cos(0.2 * y)
    xyz = np.column_stack([52000 + x.ravel(), 43000 + y.ravel(), z.ravel()])
    path = str(tmp_path / "tile.xyz")
    np.savetxt(path, xyz, fmt="%.3f")
    cloud = meshflow.read_cloud(path)
    mesh = meshflow.reconstruct(cloud, voxel=0.5)
    local = meshflow.vertex_quality(mesh, cloud)
    assert np.median(local) < 0.3 and local.max() < 1.0  # (points 0.4 m apart)
    mesh.write(str(tmp_path / "tile.ply"))
    world = meshflow.read_mesh(str(tmp_path / "tile.ply"))
    assert np.asarray(world.vertices)[:, 0].min() > 51000
    assert np.allclose(meshflow.vertex_quality(world, cloud), local, atol=0.01)
