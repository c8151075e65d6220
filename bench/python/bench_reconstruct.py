"""Python's meshflow.reconstruct against the same work in C++, measured in one run.

Python: read kurt3d scan000, reconstruct at 5 cm, write the mesh (median of --repetitions runs);
C++: BM_PipelineEndToEnd on the same file (read, the flow graph, write), Google Benchmark's
median. Prints both and their ratio. Needs the shared data ($MESHFLOW_DATA, default
../shared/data) and a Release build (PYTHONPATH=build/python).

    PYTHONPATH=build/python python3 bench/python/bench_reconstruct.py [--build build]
"""
import argparse
import json
import os
import statistics
import subprocess
import tempfile
import time

import meshflow


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", default="build")
    parser.add_argument("--repetitions", type=int, default=15)
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    data = os.environ.get("MESHFLOW_DATA", os.path.join("..", "shared", "data"))
    scan = os.path.join(data, "kurt3d", "scan000.3d")
    out = os.path.join(tempfile.gettempdir(), "meshflow_bench_python.ply")

    def once():
        start = time.perf_counter()
        mesh = meshflow.reconstruct(meshflow.read_cloud(scan), voxel=0.05, threads=args.threads)
        mesh.write(out)
        return time.perf_counter() - start, len(mesh.triangles)

    once()  # warm-up
    runs = [once() for _ in range(args.repetitions)]
    python_ms = 1e3 * statistics.median(t for t, _ in runs)

    done = subprocess.run(
        [os.path.join(args.build, "bench", "meshflow_bench"),
         f"--benchmark_filter=BM_PipelineEndToEnd/threads:{args.threads}/input:1/",
         f"--benchmark_repetitions={args.repetitions}", "--benchmark_report_aggregates_only=true",
         "--benchmark_format=json"], check=True, capture_output=True, text=True,
        env=dict(os.environ, MESHFLOW_DATA=data))
    medians = [b for b in json.loads(done.stdout)["benchmarks"] if b.get("aggregate_name") == "median"]
    cpp_ms = medians[0]["real_time"]
    print(f"kurt3d scan000, 5 cm, {args.threads} threads, read + reconstruct + write: "
          f"Python {python_ms:.1f} ms ({runs[0][1]} triangles), C++ {cpp_ms:.1f} ms, "
          f"Python / C++ = {python_ms / cpp_ms:.3f}")
    os.remove(out)


if __name__ == "__main__":
    main()
