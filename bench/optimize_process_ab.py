#!/usr/bin/env python3
"""Two (or more) `sextant` binaries on one g2o file, as whole processes: interleaved rounds (the order alternating),
each round one `BIN optimize FILE --json` per binary; medians of wall time and of the child's CPU (user + system,
from wait4).  For measuring a change to the optimize path on a shared, noisy machine: ratios to the first binary.

Usage: bench/optimize_process_ab.py BIN_A BIN_B [...] FILE.g2o ROUNDS
"""
import os
import statistics
import subprocess
import sys
import time


def main():
    bins, path, rounds = sys.argv[1:-2], sys.argv[-2], int(sys.argv[-1])
    res = {b: ([], []) for b in bins}
    for r in range(rounds):
        for b in (bins if r % 2 == 0 else bins[::-1]):
            t0 = time.perf_counter()
            p = subprocess.Popen([b, "optimize", path, "--json"], stdout=subprocess.DEVNULL)
            _, status, ru = os.wait4(p.pid, 0)
            wall = time.perf_counter() - t0
            if status != 0:
                sys.exit(f"{b} optimize {path}: exit status {status}")
            res[b][0].append(wall * 1e3)
            res[b][1].append((ru.ru_utime + ru.ru_stime) * 1e3)
    base_wall, base_cpu = (statistics.median(v) for v in res[bins[0]])
    for b in bins:
        wall, cpu = (statistics.median(v) for v in res[b])
        print(f"{b}: wall {wall:.1f} ms ({wall / base_wall:.2f}), CPU {cpu:.1f} ms ({cpu / base_cpu:.2f}), "
              f"medians of {rounds}")


if __name__ == "__main__":
    main()
