"""Fuse depth images into a TSDF map and extract its surface: here a sphere seen by a camera
circling it (depth ray-cast with NumPy), as a recorded sequence's frames would be fused.

    python3 examples/python/fuse.py [-o OUT.ply]
"""
import argparse

import numpy as np

import meshflow

K = meshflow.Intrinsics(320, 240, 300.0, 300.0, 159.5, 119.5)


def look_at(eye):
    z = -np.asarray(eye, dtype=float) / np.linalg.norm(eye)
    x = np.cross(z, [0.0, 1.0, 0.0])
    x /= np.linalg.norm(x)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = x, np.cross(z, x), z, eye
    return pose


def sphere_depth(pose, radius=0.3):
    u, v = np.meshgrid(np.arange(K.width), np.arange(K.height))
    d = np.stack([(u - K.cx) / K.fx, (v - K.cy) / K.fy, np.ones(u.shape)], -1) @ pose[:3, :3].T
    o = pose[:3, 3]
    a, b, c = (d * d).sum(-1), 2.0 * (d @ o), o @ o - radius ** 2
    disc = b * b - 4 * a * c
    t = np.where(disc > 0, (-b - np.sqrt(np.maximum(disc, 0))) / (2 * a), 0.0)
    return np.round(t * 1000).astype(np.uint16)  # millimetres, 0 = no measurement


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", default="fused.ply")
    args = parser.parse_args()
    volume = meshflow.TsdfVolume(voxel=0.01)
    for angle in np.linspace(0, 2 * np.pi, 12, endpoint=False):
        pose = look_at([np.sin(angle), 0.3, -np.cos(angle)])
        volume.integrate(sphere_depth(pose), K, pose)
    mesh = volume.extract()
    mesh.write(args.output)
    r = np.linalg.norm(mesh.vertices, axis=1)
    print(f"{volume.block_count} blocks -> {len(mesh.triangles)} triangles; radius "
          f"{r.mean():.4f} +- {r.std():.4f} m (true 0.3); wrote {args.output}")


if __name__ == "__main__":
    main()
