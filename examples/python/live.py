"""Meshes from a live loop: clouds pushed at 20 Hz into meshflow.Pipeline, each mesh handed to a
callback on a pipeline thread while the loop goes on.

    python3 examples/python/live.py [--frames N]
"""
import argparse
import time

import numpy as np

import meshflow


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=20)
    args = parser.parse_args()
    rng = np.random.default_rng(2)

    def on_mesh(result):
        if result.ok:
            print(f"frame {result.seq}: {len(result.mesh.triangles)} triangles, "
                  f"{1e3 * result.latency_s:.1f} ms after push")
        else:
            print(f"frame {result.seq} failed: {result.error}")

    with meshflow.Pipeline(on_mesh, policy="realtime", voxel=0.05) as live:
        for i in range(args.frames):  # a "sensor": a noisy sphere drifting along x
            points = rng.normal(size=(10000, 3))
            points /= np.linalg.norm(points, axis=1, keepdims=True)
            points += [0.01 * i, 0.0, 0.0]
            live.push(points.astype(np.float32), timestamp=0.05 * i)
            time.sleep(0.05)
        live.flush()
        s = live.stats()
    print(f"pushed {s['pushed']}, delivered {s['delivered']}, dropped {s['dropped']}, "
          f"latency p50 {1e3 * s['latency_p50_s']:.1f} ms")
    assert s["pushed"] == s["delivered"] + s["dropped"] + s["rejected"]


if __name__ == "__main__":
    main()
