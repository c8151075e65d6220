#!/usr/bin/env python3
"""Markdown rows for bench/RESULTS.md from a Google Benchmark JSON file.

    ./build/bench/meshflow_bench --benchmark_repetitions=3 \
        --benchmark_report_aggregates_only=true \
        --benchmark_out=bench.json --benchmark_out_format=json
    scripts/bench_tables.py bench.json [more.json ...] [--filter REGEX]

One row per benchmark and argument set: the median real time on 1 and on 2 threads (the
`threads:` argument), the speed-up, the label and the counters of the 2-thread run. Benchmarks
without a `threads:` argument get one time column. Given several files (runs of the same
build at different hours), each time is the lowest of their medians: on a shared VM a run is
only ever slowed by its neighbours.

    ./build/bench/meshflow_bench --benchmark_enable_random_interleaving=true \
        --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
        --benchmark_filter='BM_(NormalsWithIndex|Open3d|TsdfIntegrate|TsdfExtract|OptimizeStep|Meshopt)' \
        --benchmark_out=peers.json --benchmark_out_format=json
    scripts/bench_tables.py --peers peers.json

--peers prints the table against the peers instead (PEERS below: each meshflow benchmark beside
the peer's on the same input and thread count): medians of ONE run (one file only), so meshflow
and the peer were measured in the same process, interleaved, at the same load; the run's date
and load average head the table. Ratios by real time, and by CPU time (all threads) beside them:
on an oversubscribed machine a thread waiting for a core stalls its team's barriers, which
OpenMP's many short parallel regions feel far more than oneTBB's tasks.
"""
import json
import re
import sys
from collections import OrderedDict


def fmt_time(ms):
    if ms >= 100:
        return "%.0f ms" % ms
    if ms >= 10:
        return "%.1f ms" % ms
    return "%.2f ms" % ms


def fmt_counter(v):
    for unit, scale in (("G", 1e9), ("M", 1e6), ("k", 1e3)):
        if abs(v) >= scale:
            return "%.3g %s" % (v / scale, unit)
    return "%.3g" % v


SKIP = {"name", "run_name", "run_type", "repetitions", "repetition_index", "threads",
        "aggregate_name", "aggregate_unit", "iterations", "real_time", "cpu_time", "time_unit",
        "family_index", "per_family_instance_index", "label", "error_occurred", "error_message",
        "ms/frame"}  # frames/s says the same (and the counter was wrong before 2026-12-05)
TO_MS = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}


# (task, meshflow benchmark, peer, peer benchmark); keys are run names without threads.
PEERS = [
    ("normals k = 10, kurt3d scan000 (kd-tree included; meshflow also orients and interpolates)",
     "BM_NormalsWithIndex/input:1", "Open3D EstimateNormals", "BM_Open3dNormals/input:1"),
    ("normals k = 10, synthetic room 100 k points (the same)",
     "BM_NormalsWithIndex/input:0", "Open3D EstimateNormals", "BM_Open3dNormals/input:0"),
    ("TSDF integration, 5 Redwood 640 × 480 frames, 1 cm, colour",
     "BM_TsdfIntegrate/voxel_0.1mm:100/redwood:1/along_ray:0", "Open3D ScalableTSDFVolume",
     "BM_Open3dTsdfIntegrate/voxel_0.1mm:100"),
    ("TSDF integration, the same at 5 mm",
     "BM_TsdfIntegrate/voxel_0.1mm:50/redwood:1/along_ray:0", "Open3D ScalableTSDFVolume",
     "BM_Open3dTsdfIntegrate/voxel_0.1mm:50"),
    ("TSDF extraction, Redwood map, 1 cm", "BM_TsdfExtract/voxel_0.1mm:100/redwood:1",
     "Open3D ExtractTriangleMesh", "BM_Open3dTsdfExtract/voxel_0.1mm:100"),
    ("TSDF extraction, Redwood map, 5 mm", "BM_TsdfExtract/voxel_0.1mm:50/redwood:1",
     "Open3D ExtractTriangleMesh", "BM_Open3dTsdfExtract/voxel_0.1mm:50"),
    ("QEM decimation to 25 %, kurt3d", "BM_OptimizeStep/input:1/step:3",
     "meshoptimizer meshopt_simplify (1 thread)", "BM_MeshoptSimplify/input:1"),
    ("QEM decimation to 25 %, synthetic room", "BM_OptimizeStep/input:0/step:3",
     "meshoptimizer meshopt_simplify (1 thread)", "BM_MeshoptSimplify/input:0"),
]


def median_times(benchmarks, clock="real_time"):
    """{run name without threads: {threads: median `clock` time in ms}}."""
    times = {}
    for b in benchmarks:
        if b.get("aggregate_name") != "median" or b.get("error_occurred"):
            continue
        name = b["run_name"].replace("/real_time", "")
        threads = re.search(r"/threads:(\d+)", name)
        key = re.sub(r"/threads:\d+", "", name)
        t = int(threads.group(1)) if threads else 0
        times.setdefault(key, {})[t] = b[clock] * TO_MS[b["time_unit"]]
    return times


def peers_table(path):
    run = json.load(open(path))
    times = median_times(run["benchmarks"])
    cpu = median_times(run["benchmarks"], "cpu_time")
    context = run.get("context", {})
    load = ", ".join("%.2f" % v for v in context.get("load_avg", []))
    print("Run %s, %s CPUs, load average at the start %s; medians of %s repetitions, "
          "interleaved." % (context.get("date", "?"), context.get("num_cpus", "?"), load or "?",
                           next((b.get("repetitions") for b in run["benchmarks"]
                                 if b.get("repetitions")), "?")))
    print()
    print("| task | meshflow 1 / 2 threads | peer | peer 1 / 2 threads "
          "| meshflow faster by (peer / meshflow), 1 / 2 threads | the same by CPU time |")
    print("|---|---:|---|---:|---:|---:|")

    def pair(t):
        return " / ".join(fmt_time(t[n]) if n in t else "—" for n in (1, 2))

    for task, ours, peer, theirs in PEERS:
        mine, other = times.get(ours), times.get(theirs)
        if not mine or not other:
            continue  # not in this run (filtered out, or the peer not built)
        def ratios(a, b, bold):
            return " / ".join((bold % (b[n] / a[n])) if n in a and n in b else "—"
                              for n in (1, 2))
        print("| %s | %s | %s | %s | %s | %s |" % (
            task, pair(mine), peer, pair(other), ratios(mine, other, "**%.2f×**"),
            ratios(cpu[ours], cpu[theirs], "%.2f×")))


def main():
    args = sys.argv[1:]
    if "--peers" in args:
        args.remove("--peers")
        if len(args) != 1:
            sys.exit("--peers takes exactly one JSON file: every ratio comes from one run")
        peers_table(args[0])
        return
    pattern = None
    if "--filter" in args:
        i = args.index("--filter")
        pattern = re.compile(args[i + 1])
        del args[i:i + 2]
    benchmarks = [b for path in args for b in json.load(open(path))["benchmarks"]]
    rows = OrderedDict()
    for b in benchmarks:
        if b.get("aggregate_name", "median") != "median" or b.get("error_occurred"):
            continue
        name = b["run_name"].replace("/real_time", "")
        if pattern and not pattern.search(name):
            continue
        threads = re.search(r"/threads:(\d+)", name)
        key = re.sub(r"/threads:\d+", "", name)
        row = rows.setdefault(key, {"label": b.get("label", ""), "times": {}, "counters": {}})
        t = int(threads.group(1)) if threads else 0
        ms = b["real_time"] * TO_MS[b["time_unit"]]
        if t in row["times"] and row["times"][t] <= ms:
            continue
        row["times"][t] = ms
        if t in (0, 2) or not row["counters"]:
            row["counters"] = {k: v for k, v in b.items()
                               if k not in SKIP and isinstance(v, (int, float))}
    print("| benchmark | 1 thread | 2 threads | speed-up | counters (2 threads) |")
    print("|---|---:|---:|---:|---|")
    for key, row in rows.items():
        times = row["times"]
        one = times.get(1, times.get(0))
        two = times.get(2)
        speed = "%.2f×" % (one / two) if one and two else "—"
        counters = ", ".join("%s %s" % (k, fmt_counter(v)) for k, v in row["counters"].items())
        label = (" " + row["label"]) if row["label"] else ""
        print("| `%s`%s | %s | %s | %s | %s |" % (key, label, fmt_time(one) if one else "—",
                                                 fmt_time(two) if two else "—", speed, counters))


if __name__ == "__main__":
    main()
