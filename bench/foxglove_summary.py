"""The table of bench/foxglove.sh: bench/foxglove_summary.py OUT [RUN] (RUN: the MCAP run's path prefix; without it,
the bridge cases only).  A bridge case that was not run has no row."""
import json
import os
import re
import statistics
import sys


def pct(values, p):
    v = sorted(values)
    return v[min(len(v) - 1, max(0, round(p * len(v)) - 1))] if v else float("nan")


def client_lines(bridge_log):
    """Each client's last counters in the bridge's periodic stats: address -> (sent, dropped, queue max)."""
    last = {}
    for m in re.finditer(r"client (\S+): \d+ subscriptions, (\d+) sent, (\d+) dropped \(queue now \d+, at most (\d+)\)",
                         open(bridge_log).read()):
        last[m.group(1)] = tuple(int(x) for x in m.groups()[1:])
    return last


def bridge_figures(out, name):
    """One bridge case of one run: latencies p50/p99 (ms), CPU (% of a core), FUSED_POSE received per viewer,
    dropped per client, the largest client queue."""
    d = os.path.join(out, name)
    viewers = [json.load(open(os.path.join(d, f))) for f in sorted(os.listdir(d)) if re.match(r"viewer\d+\.json", f)]
    lat = [x for v in viewers for x in v["latencies_ms"]]
    ticks, hz, t0, t1 = open(os.path.join(d, "cpu.txt")).read().split()
    clients = client_lines(os.path.join(d, "bridge.log"))
    return {"viewers": len(viewers), "p50": pct(lat, 0.5), "p99": pct(lat, 0.99),
            "cpu": 100 * int(ticks) / int(hz) / (float(t1) - float(t0)),
            "received": [v["counts"].get("FUSED_POSE", 0) for v in viewers],
            "dropped": sorted(c[1] for c in clients.values()), "queue": max((c[2] for c in clients.values()), default=0)}


def bridge_row(out, name, label):
    f = bridge_figures(out, name)
    return (f"| {label} | {f['viewers']} | {f['p50']:.2f} | {f['p99']:.2f} | {f['cpu']:.1f} | "
            f"{min(f['received'])}–{max(f['received'])} of 30000 | {', '.join(map(str, f['dropped']))} | {f['queue']} |")


def before_after(runs):
    """bench/foxglove_summary.py --before-after OLD_RUN... -- NEW_RUN...: per case, each build's median CPU and
    latencies over its runs (every run's figure in brackets) and the ratio of the medians."""
    i = runs.index("--")
    builds = {"before": runs[:i], "after": runs[i + 1:]}
    print("| case | build | bridge CPU (% of a core) | added latency p50 (ms) | p99 (ms) | FUSED_POSE received per viewer, "
          "worst run | dropped (bridge), keeping up / stalled |")
    print("|---|---|---|---|---|---|---|")
    for name in ("one_viewer", "ten_viewers", "stalled_viewer"):
        medians = {}
        for build, outs in builds.items():
            figs = [bridge_figures(o, name) for o in outs if os.path.exists(os.path.join(o, name, "cpu.txt"))]
            if not figs:
                continue
            med = {k: statistics.median(f[k] for f in figs) for k in ("cpu", "p50", "p99")}
            medians[build] = med
            cell = lambda k, fmt: f"{fmt.format(med[k])} [{' '.join(fmt.format(f[k]) for f in figs)}]"
            kept = [d for f in figs for d in f["dropped"][:f["viewers"]]]
            stalled = [d for f in figs for d in f["dropped"][f["viewers"]:]]
            print(f"| {name} | {build} | {cell('cpu', '{:.1f}')} | {cell('p50', '{:.2f}')} | {cell('p99', '{:.1f}')} | "
                  f"{min(min(f['received']) for f in figs)} of 30000 | {max(kept)}"
                  f"{' / ' + ', '.join(map(str, stalled)) if stalled else ''} |")
        if len(medians) == 2:
            r = {k: medians["after"][k] / medians["before"][k] for k in ("cpu", "p50", "p99")}
            print(f"| {name} | after / before | {r['cpu']:.2f} | {r['p50']:.2f} | {r['p99']:.2f} | | |")


def mcap_row(log, label):
    text = open(log + ".convert.txt").read()
    m = re.search(r"(\d+) LCM events .* -> (\d+) MCAP messages on (\d+) channels in (\d+) chunks; ([\d.]+) MB -> ([\d.]+) MB "
                  r"\(([\d.]+)x\) in ([\d.]+) s \(([\d.]+) MB/s", text)
    check = open(log + ".check.txt").read().strip().splitlines()
    ok = "ok" if check and check[-1] == "ok" else "FAILED: " + " ".join(check[-3:])
    return f"| {label} | {m[1]} | {m[5]} | {m[6]} ({m[7]}x smaller) | {m[4]} | {m[8]} | {m[9]} | {ok} |"


def main():
    if sys.argv[1] == "--before-after":
        return before_after(sys.argv[2:])
    out, run = sys.argv[1], (sys.argv[2] if len(sys.argv) > 2 else None)
    print("Bridge: 10 bodies x 100 Hz FUSED_POSE + TRAJECTORY (1 Hz per body) + SEXTANT_STATUS (1 Hz), 30 s played by "
          "`sextant replay --realtime` on a namespace bus; viewers: tests/viewer/bridge_client.mjs --bench "
          "(@foxglove/ws-protocol).  Latency: viewer receive time - bridge receive time, every FUSED_POSE of every viewer. "
          "CPU: the bridge process's user+system time over the playing time.\n")
    print("| case | viewers | added latency p50 (ms) | p99 (ms) | bridge CPU (% of a core) | FUSED_POSE received per viewer | "
          "dropped per client (bridge) | largest client queue |")
    print("|---|---|---|---|---|---|---|---|")
    for name, label in [("one_viewer", "one viewer"), ("ten_viewers", "ten viewers"),
                        ("stalled_viewer", "one viewer + one stalled")]:
        if os.path.exists(os.path.join(out, name, "cpu.txt")):
            print(bridge_row(out, name, label))
    if run is None:
        return
    print("\nMCAP: `sextant convert mcap` (zstd level 3, 1 MiB chunks) of a 60-minute planar run, checked by "
          "tests/viewer/check_mcap.mjs (@mcap/core indexed + stream readers, CRCs, statistics, every message against the log).\n")
    print("| log | LCM events | LCM MB | MCAP MB | chunks | seconds | MB/s of LCM log | reference reader |")
    print("|---|---|---|---|---|---|---|---|")
    print(mcap_row(run + ".out", "daemon outputs (replay --out-log)"))
    print(mcap_row(run, "inputs (simulated run)"))


if __name__ == "__main__":
    main()
