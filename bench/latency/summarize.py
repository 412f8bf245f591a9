#!/usr/bin/env python3
"""Medians over several `bench/latency/run.sh BUILD JSON` runs.

Usage: bench/latency/summarize.py RUN1.json RUN2.json ...
Prints, per channel, the median p50 / p99 / max latency [ms] with the per-run values, the median daemon/raw ratios
(each run's ratio against the raw LCM round trip of the same run), and the optimizer's counters per run: keyframes
and loops per minute, events dropped per stage, odometry coalesced, graph queue depth, the 1-minute load average.
"""
import json
import statistics
import sys

RAW = "LATENCY_PONG"


def main(paths):
    if not paths:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    runs = [json.load(open(p)) for p in paths]
    channels = sorted({c for r in runs for c in r["latency"]}, key=lambda c: (c == RAW, c))
    print(f"{len(runs)} runs: " + ", ".join(paths))
    print(f"{'channel':28} {'lost':>6} {'p50 ms':>8} {'p99 ms':>8} {'max ms':>8} {'p50/raw':>8} {'p99/raw':>8}   per run p50 | p99")
    for c in channels:
        rs = [r for r in runs if c in r["latency"]]
        lat = [r["latency"][c] for r in rs]
        med = {k: statistics.median(x[k] for x in lat) for k in ("p50_ms", "p99_ms", "max_ms")}
        lost = sum(x["lost"] for x in lat)
        if c != RAW:
            r50 = statistics.median(r["latency"][c]["p50_ms"] / r["latency"][RAW]["p50_ms"] for r in rs)
            r99 = statistics.median(r["latency"][c]["p99_ms"] / r["latency"][RAW]["p99_ms"] for r in rs)
        else:
            r50 = r99 = 1.0
        per = " ".join(f"{x['p50_ms']:.3f}" for x in lat) + " | " + " ".join(f"{x['p99_ms']:.1f}" for x in lat)
        print(f"{c:28} {lost:>6} {med['p50_ms']:8.3f} {med['p99_ms']:8.2f} {med['max_ms']:8.1f} {r50:8.2f} {r99:8.2f}   {per}")
    keys = ["keyframes_per_minute", "loops_per_minute", "graph_dropped", "graph_pose_dropped", "filter_dropped",
            "odometry_coalesced", "odometry_waiting_max", "graph_queue_max", "solve_ms_p50", "solve_ms_p99",
            "busy_fraction", "graph_event_latency_ms_p50"]
    print("optimizer per run (median):")
    for k in keys:
        vals = [r["optimizer"].get(k) for r in runs]
        if any(v is None for v in vals):
            continue
        print(f"  {k:28} {statistics.median(vals):10.2f}   [" + " ".join(f"{v:.4g}" for v in vals) + "]")
    loads = [(r.get("load_begin"), r.get("load_end")) for r in runs]
    print("  load average begin/end       " + " ".join(f"{a}/{b}" for a, b in loads))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
