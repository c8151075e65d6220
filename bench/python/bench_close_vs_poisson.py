"""meshflow's open and closed (--close) reconstruction against Open3D's screened Poisson.

The input is the issue's: each closed test object scanned as a turntable scanner scans it
(`meshflow sample OBJECT --scan 8 --outliers 0.005`: eight 200 x 150 depth views from one ring
25 degrees above it, 1 mm range noise, 0.5 % outliers in the bounding box, merged without
normals or sensor; the underside and parts of the top unseen). Same cloud, same run:

* meshflow `reconstruct --voxel D/100` (D the object's diagonal), open and with `--close`;
* Open3D 0.16: statistical outlier removal (20 neighbours, 2 sigma), normals (30 nearest),
  consistent tangent-plane orientation (15), then Poisson at depth 8 and 9 without density trim
  (a closed surface, the peer of --close). Its time is the whole chain (normals included).

Measured against the object's exact surface (a uniform sample of 300 000 points with exact
normals, `meshflow sample --normals`), fractions of the diagonal:
* accuracy: mean point-to-plane distance of the mesh's vertices to the truth, split into
  vertices within half a voxel of a scanned surface point (observed) and the others (filled);
* completeness: distance of the truth points to the mesh, mean over the truth points that no
  scanned point came within a voxel of (unseen) and p95 over all;
* border edges, components (`meshflow info`), wall time.

    /usr/bin/python3 bench/python/bench_close_vs_poisson.py --meshflow build/meshflow
"""
import argparse
import json
import os
import re
import subprocess
import tempfile
import time

import numpy as np
import open3d as o3d

OBJECTS = ["sphere", "torus", "l-shape", "chamfered-cube", "box-with-hole", "box"]


def run(args):
    done = subprocess.run(args, check=True, capture_output=True, text=True)
    return done.stdout


def read_points(path):
    return np.asarray(o3d.io.read_point_cloud(path).points)


def nearest(reference, queries):
    """Index and distance of each query's nearest reference point."""
    nns = o3d.core.nns.NearestNeighborSearch(o3d.core.Tensor(reference, o3d.core.float64))
    nns.knn_index()
    index, d2 = nns.knn_search(o3d.core.Tensor(queries, o3d.core.float64), 1)
    return index.numpy()[:, 0], np.sqrt(d2.numpy()[:, 0])


def measure(mesh_path, truth, truth_normals, scan_surface, voxel, diagonal, meshflow):
    info = json.loads(run([meshflow, "info", mesh_path, "--json"]))
    mesh = o3d.io.read_triangle_mesh(mesh_path)
    vertices = np.asarray(mesh.vertices)
    index, _ = nearest(truth, vertices)
    error = np.abs(np.sum((vertices - truth[index]) * truth_normals[index], axis=1))
    _, to_scan = nearest(scan_surface, vertices)
    observed = to_scan <= 0.5 * voxel  # as tests/graph/test_scanned_objects.cpp splits them
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.t.geometry.TriangleMesh.from_legacy(mesh))
    completeness = scene.compute_distance(o3d.core.Tensor(truth.astype(np.float32))).numpy()
    _, truth_to_scan = nearest(scan_surface, truth)
    unseen = truth_to_scan > voxel
    return {
        "observed_mean": float(error[observed].mean()) / diagonal,
        "filled_mean": float(error[~observed].mean()) / diagonal if (~observed).any() else 0.0,
        "unseen_completeness_mean": float(completeness[unseen].mean()) / diagonal,
        "completeness_p95": float(np.percentile(completeness, 95)) / diagonal,
        "border_edges": info["border_edges"],
        "components": info["components"],
        "closed": info["closed"],
        "unseen_share": float(unseen.mean()),
    }


def open3d_poisson(scan_path, directory, depths):
    """Poisson meshes of the scan at each depth; seconds of the whole chain per depth."""
    pcd = o3d.io.read_point_cloud(scan_path)
    start = time.perf_counter()
    pcd, _ = pcd.remove_statistical_outlier(nb_neighbors=20, std_ratio=2.0)
    pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn=30))
    pcd.orient_normals_consistent_tangent_plane(15)
    normals_s = time.perf_counter() - start
    out = {}
    for depth in depths:
        start = time.perf_counter()
        mesh, _ = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(pcd, depth=depth)
        seconds = normals_s + time.perf_counter() - start
        path = os.path.join(directory, f"poisson{depth}.ply")
        o3d.io.write_triangle_mesh(path, mesh)
        out[f"Open3D Poisson {depth}"] = (path, seconds)
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--meshflow", default="build/meshflow")
    parser.add_argument("--objects", default=",".join(OBJECTS))
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--depths", default="8,9",
                        help="Open3D Poisson depths, comma-separated; empty: meshflow only")
    parser.add_argument("--json", help="write every figure to this file")
    args = parser.parse_args()
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    results = {}
    for name in args.objects.split(","):
        with tempfile.TemporaryDirectory() as directory:
            scan = os.path.join(directory, "scan.ply")
            report = run([args.meshflow, "sample", name, "--scan", "8", "--outliers", "0.005",
                          "-o", scan])
            diagonal = float(re.search(r"diagonal ([0-9.]+) m", report).group(1))
            outliers = int(re.search(r"([0-9]+) outliers", report).group(1))
            voxel = 0.01 * diagonal
            truth_path = os.path.join(directory, "truth.ply")
            run([args.meshflow, "sample", name, "--points", "300000", "--normals", "-o",
                 truth_path])
            truth_cloud = o3d.io.read_point_cloud(truth_path)
            truth = np.asarray(truth_cloud.points)
            truth_normals = np.asarray(truth_cloud.normals)
            points = read_points(scan)
            scan_surface = points[: len(points) - outliers]
            meshes = {}
            for label, extra in (("meshflow open", []), ("meshflow --close", ["--close"])):
                path = os.path.join(directory, label.split()[-1].strip("-") + ".ply")
                doc = json.loads(run([args.meshflow, "reconstruct", scan, "-o", path, "--voxel",
                                      f"{voxel:.6g}", "--threads", str(args.threads), "--json"]
                                     + extra))
                meshes[label] = (path, doc["time_ms"] / 1e3)
            depths = [int(d) for d in args.depths.split(",") if d]
            if depths:
                meshes.update(open3d_poisson(scan, directory, depths))
            results[name] = {}
            for label, (path, seconds) in meshes.items():
                figures = measure(path, truth, truth_normals, scan_surface, voxel, diagonal,
                                  args.meshflow)
                figures["seconds"] = seconds
                results[name][label] = figures
                print(f"{name:15s} {label:17s} observed {figures['observed_mean']:.2e} "
                      f"filled {figures['filled_mean']:.2e} unseen {figures['unseen_completeness_mean']:.2e} "
                      f"p95 {figures['completeness_p95']:.2e} border {figures['border_edges']} "
                      f"components {figures['components']} {seconds * 1e3:.0f} ms", flush=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=1)


if __name__ == "__main__":
    main()
