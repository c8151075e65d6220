#!/usr/bin/env python3
"""Serial instructions of a 1-thread callgrind profile: the part of a run no second thread can share.

    valgrind --tool=callgrind --callgrind-out-file=run.out \\
        build/meshflow reconstruct $MESHFLOW_DATA/kurt3d/scan000.3d -o /tmp/k.ply --voxel 0.05 --threads 1
    bench/callgrind_serial.py run.out [TOP]

Each function's exclusive instructions count as parallel in the proportion of its inclusive cost
that reaches it through callers running inside a oneTBB parallel algorithm's task (start_for,
start_reduce, function_invoker, parallel_sort's tasks, ...), serial otherwise; the flow graph's
node bodies are not parallel algorithms. Context-insensitive (callgrind keeps one caller level),
recursion edges ignored. Prints the total, the serial instructions, Amdahl's 2-thread bound
W / (S + (W - S) / 2), and the TOP (default 25) serial functions. Load-independent."""
import re
import subprocess
import sys

PARALLEL = re.compile(r"start_for<|start_reduce<|function_invoker<|start_deterministic_reduce<|"
                      r"quick_sort_pretest|quick_sort_range|start_scan<|for_each_iteration_task|"
                      r"feeder_item_task")
ROW = re.compile(r"\s*([\d,]+)\s+\([^)]*\)\s+(\*|<)?\s*(.*)$")


def annotate(path, *args):
    return subprocess.run(["callgrind_annotate", "--threshold=100", *args, path],
                          capture_output=True, text=True, check=True).stdout


def main():
    path = sys.argv[1]
    top = int(sys.argv[2]) if len(sys.argv) > 2 else 25
    callers = {}  # function -> [(instructions through that caller, caller)]
    for block in annotate(path, "--tree=caller", "--inclusive=yes").split("\n\n"):
        name, edges = None, []
        for line in block.splitlines():
            m = ROW.match(line)
            if not m:
                continue
            if m.group(2) == "*":
                name = m.group(3)
            elif m.group(2) == "<":
                caller = re.sub(r" \([\d,]+x\)( \[[^\]]*\])$", r"\1", m.group(3))
                edges.append((int(m.group(1).replace(",", "")), caller))
        if name is not None:
            callers[name] = edges
    exclusive = {}
    for line in annotate(path, "--inclusive=no").splitlines():
        m = ROW.match(line)
        if m and m.group(2) is None and "PROGRAM TOTALS" not in m.group(3):
            exclusive[m.group(3)] = exclusive.get(m.group(3), 0) + int(m.group(1).replace(",", ""))
    share = {}  # function -> fraction reached inside parallel tasks

    def parallel_share(name, depth=0):
        if name in share:
            return share[name]
        if PARALLEL.search(name):
            share[name] = 1.0
            return 1.0
        share[name] = 0.0  # cycles: provisional
        if depth > 80:
            return 0.0
        plain = re.sub(r"'\d+", "", name)
        edges = [(c, k) for c, k in callers.get(name, []) if re.sub(r"'\d+", "", k) != plain]
        total = sum(c for c, _ in edges)
        if total > 0:
            share[name] = sum(c * parallel_share(k, depth + 1) for c, k in edges) / total
        return share[name]

    rows = sorted(((e * (1.0 - parallel_share(n)), e, n) for n, e in exclusive.items()),
                  reverse=True)
    work = sum(exclusive.values())
    serial = sum(r[0] for r in rows)
    print(f"total {work / 1e6:.1f} M instructions, serial {serial / 1e6:.1f} M "
          f"({100 * serial / work:.1f} %), Amdahl 2 threads {work / (serial + (work - serial) / 2):.2f}x")
    for s, e, n in rows[:top]:
        print(f"{s / 1e6:8.2f} {e / 1e6:8.2f}  {n[:160]}")


if __name__ == "__main__":
    main()
