"""meshflow and Open3D from Python on the same inputs, in one run (Debian: python3-open3d).

1. kurt3d scan000 (77 k points): meshflow.reconstruct at 5 cm (normals, distance, marching
   cubes, clean-up) against Open3D's estimate_normals (k = 10), normals towards the scanner,
   and Poisson reconstruction (depth 9); the cloud is read once (meshflow.read_cloud) for both.
2. The 5 Redwood frames at 1 cm: meshflow.TsdfVolume.integrate against Open3D's
   ScalableTSDFVolume.integrate (truncation 4 cm, both), then each one's mesh extraction.

Times are medians over --repetitions runs, in milliseconds, on --threads threads.

    PYTHONPATH=build/python MESHFLOW_DATA=../shared/data python3 bench/python/bench_vs_open3d.py
"""
import argparse
import os
import statistics
import time

import numpy as np
import open3d as o3d

import meshflow


def median_ms(fn, repetitions):
    fn()  # warm-up
    times = []
    for _ in range(repetitions):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return 1e3 * statistics.median(times)


def read_redwood(directory):
    lines = open(os.path.join(directory, "trajectory.log")).read().split("\n")
    poses = [np.array([[float(x) for x in lines[5 * i + r].split()] for r in range(1, 5)])
             for i in range(len(lines) // 5)]
    frames = []
    for i, pose in enumerate(poses):
        depth = np.asarray(o3d.io.read_image(os.path.join(directory, "depth", f"{i:05d}.png")))
        frames.append((depth, pose))
    return frames


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repetitions", type=int, default=5)
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    data = os.environ.get("MESHFLOW_DATA", os.path.join("..", "shared", "data"))
    os.environ["OMP_NUM_THREADS"] = str(args.threads)

    cloud = meshflow.read_cloud(os.path.join(data, "kurt3d", "scan000.3d"))
    mesh = meshflow.reconstruct(cloud, voxel=0.05, threads=args.threads)
    mf = median_ms(lambda: meshflow.reconstruct(cloud, voxel=0.05, threads=args.threads),
                   args.repetitions)

    def open3d_poisson():
        pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(cloud.points.astype(np.float64)))
        pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn=10))
        pcd.orient_normals_towards_camera_location(np.array(cloud.sensor_origin or (0, 0, 0)))
        return o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(pcd, depth=9)[0]

    o3d_mesh = open3d_poisson()
    o3d_ms = median_ms(open3d_poisson, args.repetitions)
    print(f"kurt3d scan000 ({len(cloud)} points), {args.threads} threads:")
    print(f"  meshflow.reconstruct 5 cm          {mf:8.1f} ms  {len(mesh.triangles):7d} triangles")
    print(f"  Open3D normals + Poisson depth 9   {o3d_ms:8.1f} ms  "
          f"{len(o3d_mesh.triangles):7d} triangles   ({o3d_ms / mf:.1f}x meshflow's time)")

    frames = read_redwood(os.path.join(data, "rgbd_redwood"))
    k = meshflow.Intrinsics(640, 480, 525.0, 525.0, 319.5, 239.5)
    o3d_k = o3d.camera.PinholeCameraIntrinsic(640, 480, 525.0, 525.0, 319.5, 239.5)

    def meshflow_fuse():
        volume = meshflow.TsdfVolume(voxel=0.01, truncation=4.0)
        for depth, pose in frames:
            volume.integrate(depth, k, pose)
        return volume

    def open3d_fuse():
        volume = o3d.pipelines.integration.ScalableTSDFVolume(
            voxel_length=0.01, sdf_trunc=0.04,
            color_type=o3d.pipelines.integration.TSDFVolumeColorType.NoColor)
        for depth, pose in frames:
            color = o3d.geometry.Image(np.zeros((480, 640, 3), dtype=np.uint8))
            rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
                color, o3d.geometry.Image(depth), depth_scale=1000.0, depth_trunc=4.0,
                convert_rgb_to_intensity=False)
            volume.integrate(rgbd, o3d_k, np.linalg.inv(pose))
        return volume

    n = len(frames)
    mf_fuse = median_ms(meshflow_fuse, args.repetitions) / n
    o3d_fuse = median_ms(open3d_fuse, args.repetitions) / n
    mf_volume, o3d_volume = meshflow_fuse(), open3d_fuse()
    mf_extract = median_ms(lambda: mf_volume.extract(incremental=False), args.repetitions)
    o3d_extract = median_ms(o3d_volume.extract_triangle_mesh, args.repetitions)
    print(f"Redwood, {n} frames at 1 cm, {args.threads} threads:")
    print(f"  integrate per frame   meshflow {mf_fuse:7.1f} ms   Open3D {o3d_fuse:7.1f} ms   "
          f"({o3d_fuse / mf_fuse:.1f}x)")
    print(f"  extract               meshflow {mf_extract:7.1f} ms   Open3D {o3d_extract:7.1f} ms   "
          f"({o3d_extract / mf_extract:.1f}x); triangles {len(mf_volume.extract().triangles)} vs "
          f"{len(o3d_volume.extract_triangle_mesh().triangles)}")


if __name__ == "__main__":
    main()
