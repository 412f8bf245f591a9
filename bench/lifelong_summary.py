"""Summary of bench/lifelong.sh: per-segment tables and the targets of the lifelong benchmark, as Markdown.
usage: lifelong_summary.py OUT LCMTYPES_PY TESTS_E2E"""
import glob
import json
import os
import sys

out = sys.argv[1]
sys.path.insert(0, sys.argv[2])
sys.path.insert(0, sys.argv[3])


def load(path):
    with open(path) as f:
        return json.load(f)


def graph_stage(seg):
    return seg["stages"].get("graph", {"p50_ms": 0, "p99_ms": 0, "max_ms": 0})


def rtf(segs):
    wall = sum(s["wall_s"] for s in segs)
    return sum(s["data_s"] for s in segs) / wall if wall > 0 else 0


runs = sorted(glob.glob(os.path.join(out, "*_*min_seed*.lifelong.json")))
print("## Offline replay, default config (lifelong on), per run\n")
print("| run | real-time factor | first 5 min | last 10 min | flat ratio | graph p99 max over segments (ms) | graph max (ms) |"
      " peak RSS (MB) | RSS min 20 -> end (MB) | graph keyframes at end | ATE graph (m) | ATE full history (m) |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")
targets = []
for path in runs:
    name = os.path.basename(path).replace(".lifelong.json", "")
    r = load(path)
    segs = r["segments"]
    first, last10 = segs[:1], [s for s in segs if s["start_s"] >= segs[-1]["start_s"] + segs[-1]["data_s"] - 600 - 1e-6]
    flat = rtf(last10) / rtf(first) if rtf(first) > 0 else 0
    p99 = max(graph_stage(s)["p99_ms"] for s in segs)
    mx = max(graph_stage(s)["max_ms"] for s in segs)
    peak = int(open(path.replace(".json", ".maxrss")).read().split()[-1]) / 1024
    rss20 = [s["rss_kb"] / 1024 for s in segs if s["start_s"] + s["data_s"] >= 1200 - 1e-6]
    rss_txt = f"{rss20[0]:.0f} -> {rss20[-1]:.0f}" if len(rss20) > 1 else "-"
    ate = load(path.replace(".json", ".eval.json"))["ate_rmse"]
    full_eval = path.replace(".lifelong.json", ".full.eval.json")
    ate_full = load(full_eval)["ate_rmse"] if os.path.exists(full_eval) else None
    kf = segs[-1]["graph"].get("graph_keyframes", 0)
    print(f"| {name} | {r['realtime_factor']:.1f} | {rtf(first):.1f} | {rtf(last10):.1f} | {flat:.2f} | {p99:.2f} | {mx:.1f} |"
          f" {peak:.0f} | {rss_txt} | {kf} | {ate:.4f} | {'-' if ate_full is None else f'{ate_full:.4f}'} |")
    minutes = round(r["duration_s"] / 60)
    if minutes >= 60:
        targets.append((f"{name}: flat (last 10 min >= 0.8 x first 5 min)", f"{flat:.2f}", flat >= 0.8))
        targets.append((f"{name}: fast (>= 50x real time)", f"{r['realtime_factor']:.1f}x", r["realtime_factor"] >= 50))
        targets.append((f"{name}: graph p99 <= 20 ms in every segment", f"{p99:.2f} ms", p99 <= 20))
        targets.append((f"{name}: graph max <= 100 ms in every segment", f"{mx:.1f} ms", mx <= 100))
        if len(rss20) > 1:
            growth = rss20[-1] / rss20[0] - 1
            targets.append((f"{name}: replay RSS flat from minute 20 (within 10 %)", f"{100 * growth:+.1f} %", abs(growth) <= 0.10))
    if minutes <= 5 and ate_full is not None:
        targets.append((f"{name}: ATE within 10 % of full history", f"{ate:.4f} vs {ate_full:.4f}", ate <= 1.10 * ate_full))

print("\n## Per segment (planar, longest run, seed 1)\n")
longest = sorted(runs, key=lambda p: load(p)["duration_s"])
planar = [p for p in longest if "planar_" in os.path.basename(p) and "seed1" in p]
if planar:
    r = load(planar[-1])
    print("| start (min) | real-time factor | graph p50 / p99 / max (ms) | RSS (MB) | graph keyframes | factors | thinnings |")
    print("|---|---|---|---|---|---|---|")
    for s in r["segments"]:
        g = graph_stage(s)
        print(f"| {s['start_s'] / 60:.0f} | {s['realtime_factor']:.1f} | {g['p50_ms']:.3f} / {g['p99_ms']:.2f} / {g['max_ms']:.1f} |"
              f" {s['rss_kb'] / 1024:.0f} | {s['graph'].get('graph_keyframes', 0)} | {s['graph'].get('graph_factors', 0)} |"
              f" {s['graph'].get('thinnings', 0)} |")

bus = os.path.join(out, "live_bus.lcm")
if os.path.exists(bus):
    from lcmlog import read_log
    from sextant import status_t
    print("\n## Live: sextantd fed at 10x\n")
    sizes, first_t, last_t, traj_bytes = {}, None, None, 0
    queue_max, queue_cap, dropped, age_max = 0, 0, 0, 0
    for ts, channel, data in read_log(bus):
        sizes[channel] = max(sizes.get(channel, 0), len(data))
        if channel == "TRAJECTORY":
            traj_bytes += len(data)
            first_t = ts if first_t is None else first_t
            last_t = ts
        if channel == "SEXTANT_STATUS":
            s = status_t.decode(data)
            for st in s.stages:
                if st.name == "graph":
                    queue_max = max(queue_max, st.queue_depth)
                    queue_cap = st.queue_capacity
                if st.name == "graph_pose":
                    c = dict(zip(st.counter_names, st.counter_values))
                    age_max = max(age_max, c.get("correction_age_us_max", 0))
            last_status = s
    for st in last_status.stages:
        dropped += st.dropped
    drops_in = sum(c.dropped for c in last_status.channels)
    wall = (last_t - first_t) * 1e-6 if first_t is not None and last_t > first_t else 0
    rate = traj_bytes / wall if wall > 0 else 0
    rss = [int(line.split()[1]) for line in open(os.path.join(out, "live_rss.txt")) if len(line.split()) == 2]
    print(f"- graph queue: at most {queue_max} of {queue_cap}; events dropped by stages {dropped}, at intake {drops_in}")
    print(f"- correction age: at most {age_max / 1e6:.3f} s (data time)")
    print(f"- TRAJECTORY: {rate / 1024:.1f} KB/s over {wall:.0f} s of wall time at 10x, i.e. {rate / 10 / 1024:.1f} KB per "
          f"second of data (what a robot running in real time sends); largest message {sizes.get('TRAJECTORY', 0) / 1024:.1f} KB")
    print(f"- largest message on any channel: {max(sizes.values()) / 1024:.1f} KB ({max(sizes, key=sizes.get)})")
    if rss:
        n = len(rss)
        print(f"- sextantd RSS: {rss[0] / 1024:.0f} MB at start, {rss[n // 3] / 1024:.0f} MB at a third, {rss[-1] / 1024:.0f} MB at the end")
        targets.append(("daemon RSS after the run <= 200 MB", f"{rss[-1] / 1024:.0f} MB", rss[-1] <= 200 * 1024))
        # The RSS swings by several MB as thinnings allocate a new graph and free the old one: compare the peaks of the
        # middle and the last third (from minute 20 of a 60-minute run on).
        middle, last = max(rss[n // 3:2 * n // 3]), max(rss[2 * n // 3:])
        growth = last / middle - 1
        print(f"- sextantd RSS peak: {middle / 1024:.1f} MB in the middle third, {last / 1024:.1f} MB in the last")
        targets.append(("daemon RSS flat from a third of the run to the end (peaks, within 10 %)", f"{100 * growth:+.1f} %", abs(growth) <= 0.10))
    targets.append(("daemon at 10x: graph queue never full", f"{queue_max} / {queue_cap}", queue_max < queue_cap))
    targets.append(("daemon at 10x: no event dropped", f"{dropped + drops_in}", dropped + drops_in == 0))
    targets.append(("daemon at 10x: correction age <= 1 s", f"{age_max / 1e6:.3f} s", age_max <= 1e6))
    targets.append(("TRAJECTORY <= 100 KB/s per second of data (real time)", f"{rate / 10 / 1024:.1f} KB/s", rate / 10 <= 100 * 1024))
    targets.append(("TRAJECTORY <= 100 KB/s of wall time while fed at 10x", f"{rate / 1024:.1f} KB/s", rate <= 100 * 1024))
    targets.append(("no message over 64 KB", f"{max(sizes.values()) / 1024:.1f} KB", max(sizes.values()) <= 64 * 1024))

print("\n## Targets\n")
print("| target | measured | met |")
print("|---|---|---|")
for name, value, ok in targets:
    print(f"| {name} | {value} | {'yes' if ok else 'no'} |")
