#!/usr/bin/env python3
"""Amdahl's model of a meshflow-mpi run for 8, 32 and 128 nodes, from its --json phases.

    bench/amdahl_model.py RUN.json [--link-gbit 10]

S = rank 0's serial phases (wall s, and CPU s: under load the wall time of a serial phase
includes waiting for a core), W = every rank's parallel work (CPU s of decide, partition, chunks,
weld). Predicted wall on N nodes: T(N) = S + W / N + G(N), where G is rank 0 receiving the
welded mesh ((N - 1) / N of `gathered bytes` scaled to the whole mesh) over a link of
--link-gbit; the partition's byte ranges are assumed to be read at a bandwidth that grows with
the nodes (a parallel file system), the chunks to keep every node busy (chunks >= 4 N).
Prints a Markdown table."""
import json
import sys


def main():
    args = sys.argv[1:]
    link = 10.0
    if "--link-gbit" in args:
        i = args.index("--link-gbit")
        link = float(args[i + 1])
        del args[i:i + 2]
    d = json.load(open(args[0]))
    ranks = d["timing"]["ranks"]
    serial_wall = sum(p["wall_s"] for r in ranks for p in r["phases"] if p["serial"])
    serial_cpu = sum(p["cpu_s"] for r in ranks for p in r["phases"] if p["serial"])
    work = sum(p["work_s"] for r in ranks for p in r["phases"] if not p["serial"])
    n = len(ranks)
    mesh_bytes = d.get("gathered_bytes", 0) * n / max(n - 1, 1)  # the whole welded mesh
    print(f"| nodes | T(N) s (S wall {serial_wall:.2f} s) | speedup | T(N) s (S CPU "
          f"{serial_cpu:.2f} s) | speedup |")
    print("|---:|---:|---:|---:|---:|")
    for nodes in (1, 8, 32, 128):
        gather = mesh_bytes * (nodes - 1) / nodes * 8 / (link * 1e9)
        cells = []
        for s in (serial_wall, serial_cpu):
            t = s + work / nodes + gather
            cells += [f"{t:.2f}", f"{(s + work) / t:.1f}×"]
        print(f"| {nodes} | " + " | ".join(cells) + " |")
    f_wall = serial_wall / (serial_wall + work)
    f_cpu = serial_cpu / (serial_cpu + work)
    print(f"\nf = {f_wall:.4f} (serial wall) / {f_cpu:.4f} (serial CPU) of {serial_wall + work:.1f} s "
          f"one-core work ({n} ranks, parallel work W = {work:.1f} s, mesh "
          f"{mesh_bytes / 1e6:.0f} MB over {link:g} Gbit/s)")


if __name__ == "__main__":
    main()
