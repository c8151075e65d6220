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


def main():
    args = sys.argv[1:]
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
