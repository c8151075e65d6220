"""Reconstruct a point cloud file (or a sphere sampled here) and write the mesh.

    python3 examples/python/reconstruct.py [CLOUD] [-o OUT.ply] [--voxel METRES]
"""
import argparse

import numpy as np

import meshflow


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cloud", nargs="?", help="PLY, PCD, XYZ, 3DTK .3d or LAS file")
    parser.add_argument("-o", "--output", default="mesh.ply")
    parser.add_argument("--voxel", type=float, default=0.0, help="0: 3x the point spacing")
    args = parser.parse_args()
    if args.cloud:
        cloud = meshflow.read_cloud(args.cloud)
    else:  # 50 000 points on a unit sphere, no normals: orientation by propagation
        rng = np.random.default_rng(1)
        points = rng.normal(size=(50000, 3))
        points /= np.linalg.norm(points, axis=1, keepdims=True)
        cloud = meshflow.Cloud(points)
    mesh = meshflow.reconstruct(cloud, voxel=args.voxel)
    mesh.write(args.output)
    figures = meshflow.evaluate(mesh, cloud)
    print(f"{len(cloud)} points -> {len(mesh.vertices)} vertices, {len(mesh.triangles)} "
          f"triangles; mesh to points mean {figures['mesh_to_reference']['mean']:.5f} m; "
          f"watertight: {figures['topology']['watertight']}; wrote {args.output}")


if __name__ == "__main__":
    main()
