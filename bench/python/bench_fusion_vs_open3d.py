"""Fused maps of meshflow and Open3D on the same posed depth frames, against exact truth.

For each of meshflow's closed test objects, `meshflow sample OBJECT --orbit N` writes N depth
frames of a camera circling it (TUM layout, 1 mm range noise). Both fuse them at the same voxel
and truncation: meshflow with `meshflow run DIR --fuse` (its default filtering and clean-up),
Open3D 0.16 with ScalableTSDFVolume (integrate + extract_triangle_mesh). Each mesh is measured
with `meshflow eval`:

  accuracy      mean distance of the mesh's surface to the exact object (eval --object)
  completeness  mean distance of 200 000 points on the exact object to the mesh
                (eval --reference: truth -> mesh; a hole shows as a large distance)

both as fractions of the object's bounding-box diagonal, plus the mesh's border edges.

With MESHFLOW_DATA set, the same for the shared Redwood frames (no exact truth): the reference
is every second valid pixel of every frame, back-projected into the world (frames -> mesh is the
completeness, mesh -> frames the accuracy), in metres.

    PYTHONPATH=build/python python3 bench/python/bench_fusion_vs_open3d.py [--voxel 0.01]
"""
import argparse
import json
import os
import subprocess
import tempfile
import time

import numpy as np
import open3d as o3d

OBJECTS = ["sphere", "torus", "l-shape", "chamfered-cube", "box-with-hole", "box"]


def meshflow_cli():
    return os.environ.get("MESHFLOW_CLI", os.path.join("build", "meshflow"))


def cli(*args):
    out = subprocess.run([meshflow_cli(), *args], check=True, capture_output=True, text=True)
    return out.stdout


def evaluate(mesh, obj, truth):
    exact = json.loads(cli("eval", mesh, "--object", obj, "--json"))
    against = json.loads(cli("eval", mesh, "--reference", truth, "--json"))
    diagonal = exact["reference"]["diagonal"]
    topology = against["topology"]
    return {
        "accuracy": exact["surface_to_truth"]["mean"] / diagonal,
        "completeness": against["reference_to_mesh"]["mean"] / diagonal,
        "completeness_p95": against["reference_to_mesh"]["p95"] / diagonal,
        "boundary_edges": topology["boundary_edges"],
        "triangles": against["triangles"],
    }


def open3d_fuse(directory, voxel, truncation_voxels, out_path):
    camera = json.load(open(os.path.join(directory, "camera.json")))
    m = camera["intrinsic_matrix"]
    k = o3d.camera.PinholeCameraIntrinsic(camera["width"], camera["height"], m[0], m[4], m[6], m[7])
    volume = o3d.pipelines.integration.ScalableTSDFVolume(
        voxel_length=voxel, sdf_trunc=truncation_voxels * voxel,
        color_type=o3d.pipelines.integration.TSDFVolumeColorType.RGB8)
    depth_files = [l.split()[1] for l in open(os.path.join(directory, "depth.txt"))
                   if l.strip() and not l.startswith("#")]
    rgb_files = [l.split()[1] for l in open(os.path.join(directory, "rgb.txt"))
                 if l.strip() and not l.startswith("#")]
    poses = [[float(x) for x in l.split()[1:]] for l in open(os.path.join(directory, "groundtruth.txt"))
             if l.strip() and not l.startswith("#")]
    start = time.perf_counter()
    for depth_file, rgb_file, p in zip(depth_files, rgb_files, poses):
        depth = o3d.io.read_image(os.path.join(directory, depth_file))
        color = o3d.io.read_image(os.path.join(directory, rgb_file))
        rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
            color, depth, depth_scale=5000.0, depth_trunc=10.0, convert_rgb_to_intensity=False)
        pose = np.eye(4)
        x, y, z, w = p[3:7]
        pose[:3, :3] = o3d.geometry.get_rotation_matrix_from_quaternion([w, x, y, z])
        pose[:3, 3] = p[0:3]
        volume.integrate(rgbd, k, np.linalg.inv(pose))
    mesh = volume.extract_triangle_mesh()
    seconds = time.perf_counter() - start
    o3d.io.write_triangle_mesh(out_path, mesh)
    return seconds


def redwood_frames(directory):
    lines = [l for l in open(os.path.join(directory, "trajectory.log")).read().split("\n") if l]
    poses = [np.array([[float(x) for x in lines[5 * i + r].split()] for r in range(1, 5)])
             for i in range(len(lines) // 5)]
    depth = sorted(os.listdir(os.path.join(directory, "depth")))
    color = sorted(os.listdir(os.path.join(directory, "color")))
    return [(os.path.join(directory, "depth", d), os.path.join(directory, "color", c), p)
            for d, c, p in zip(depth, color, poses)]


def redwood_reference(frames, k, path):
    points = []
    for depth_file, _, pose in frames:
        depth = np.asarray(o3d.io.read_image(depth_file)).astype(np.float64) / 1000.0
        v, u = np.mgrid[0:depth.shape[0]:2, 0:depth.shape[1]:2]
        z = depth[v, u]
        valid = (z > 0.1) & (z < 10.0)
        x = (u[valid] - k[2]) / k[0] * z[valid]
        y = (v[valid] - k[3]) / k[1] * z[valid]
        camera = np.stack([x, y, z[valid], np.ones_like(x)])
        points.append((pose @ camera)[:3].T)
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.concatenate(points)))
    o3d.io.write_point_cloud(path, cloud)


def bench_redwood(directory, args, work):
    frames = redwood_frames(directory)
    k = (525.0, 525.0, 319.5, 239.5)
    reference = os.path.join(work, "redwood_frames.ply")
    redwood_reference(frames, k, reference)
    out = os.path.join(work, "redwood_meshflow")
    start = time.perf_counter()
    cli("run", directory, "--fuse", "--voxel", str(args.voxel), "--truncation",
        str(args.truncation), "-o", out, "-q", *args.meshflow_args.split())
    mf_seconds = time.perf_counter() - start
    volume = o3d.pipelines.integration.ScalableTSDFVolume(
        voxel_length=args.voxel, sdf_trunc=args.truncation * args.voxel,
        color_type=o3d.pipelines.integration.TSDFVolumeColorType.RGB8)
    o3d_k = o3d.camera.PinholeCameraIntrinsic(640, 480, *k)
    start = time.perf_counter()
    for depth_file, color_file, pose in frames:
        rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
            o3d.io.read_image(color_file), o3d.io.read_image(depth_file), depth_scale=1000.0,
            depth_trunc=10.0, convert_rgb_to_intensity=False)
        volume.integrate(rgbd, o3d_k, np.linalg.inv(pose))
    o3d_path = os.path.join(work, "redwood_open3d.ply")
    o3d.io.write_triangle_mesh(o3d_path, volume.extract_triangle_mesh())
    o3d_seconds = time.perf_counter() - start
    print(f"Redwood, {len(frames)} frames (metres: accuracy = mesh -> frames, completeness = "
          f"frames -> mesh)")
    for tool, path, seconds in (("meshflow", os.path.join(out, "fused.ply"), mf_seconds),
                                ("Open3D", o3d_path, o3d_seconds)):
        r = json.loads(cli("eval", path, "--reference", reference, "--json"))
        print(f"{'redwood':15} {tool:9} {r['mesh_to_reference']['mean']:9.2e} "
              f"{r['reference_to_mesh']['mean']:9.2e} {r['reference_to_mesh']['p95']:9.2e} "
              f"{r['topology']['boundary_edges']:9d} {seconds:7.2f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--voxel", type=float, default=0.01)
    parser.add_argument("--truncation", type=float, default=4.0, help="voxels")
    parser.add_argument("--frames", type=int, default=24)
    parser.add_argument("--objects", default=",".join(OBJECTS))
    parser.add_argument("--meshflow-args", default="", help="extra arguments of meshflow run")
    parser.add_argument("--redwood", default=os.path.join(
        os.environ.get("MESHFLOW_DATA", os.path.join("..", "shared", "data")), "rgbd_redwood"))
    args = parser.parse_args()
    work = tempfile.mkdtemp(prefix="meshflow-fusion-")
    print(f"voxel {args.voxel} m, truncation {args.truncation} voxels, {args.frames} frames; "
          f"fractions of the diagonal (accuracy: mesh -> truth mean; completeness: truth -> mesh "
          f"mean / p95)")
    print(f"{'object':15} {'tool':9} {'accuracy':>9} {'complete':>9} {'p95':>9} "
          f"{'border e.':>9} {'time s':>7}")
    for obj in [o for o in args.objects.split(",") if o]:
        orbit = os.path.join(work, obj)
        truth = os.path.join(work, obj + "_truth.ply")
        cli("sample", obj, "--orbit", str(args.frames), "-o", orbit, "-q")
        cli("sample", obj, "--points", "200000", "-o", truth, "-q")
        out = os.path.join(work, obj + "_meshflow")
        start = time.perf_counter()
        cli("run", orbit, "--fuse", "--voxel", str(args.voxel), "--truncation",
            str(args.truncation), "-o", out, "-q", *args.meshflow_args.split())
        mf_seconds = time.perf_counter() - start
        o3d_path = os.path.join(work, obj + "_open3d.ply")
        o3d_seconds = open3d_fuse(orbit, args.voxel, args.truncation, o3d_path)
        for tool, path, seconds in (("meshflow", os.path.join(out, "fused.ply"), mf_seconds),
                                    ("Open3D", o3d_path, o3d_seconds)):
            r = evaluate(path, obj, truth)
            print(f"{obj:15} {tool:9} {r['accuracy']:9.2e} {r['completeness']:9.2e} "
                  f"{r['completeness_p95']:9.2e} {r['boundary_edges']:9d} {seconds:7.2f}")
    if os.path.isdir(args.redwood):
        bench_redwood(args.redwood, args, work)


if __name__ == "__main__":
    main()
