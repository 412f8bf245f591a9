"""A real robot next to a flood of one-off names and impossible loop closures (bench/flood/run.sh runs it).

make OUT.lcm START [robot-only]: one robot ("robot") driving a circle at 50 Hz for the whole run, and around it,
in phases:
  quiet   [0, 20 s)     the robot alone (the baseline of its latency)
  names   [20, 80 s)    60,000 distinct body names, two odometry messages each, 2,000 messages/s
  loops   [80, 130 s)   100,000 distinct impossible loop closures, 2,000/s: a third ahead of the robot's odometry
                        (they wait for it), a third before its first message (unmatchable), a third of bodies that
                        never sent odometry
  after   [130, 160 s)  the robot alone again (what the flood left behind)
START is the robot's first utime (microseconds); lcm-logplayer replays the log in real time.  robot-only: the robot
alone for the whole run (the baseline of the daemon's memory).

summarize BUS.lcm RSS.txt [JSON]: from lcm-logger's recording of the bus (receipt times) and the daemon's RSS
sampled every 0.2 s (lines "microseconds since lcm-logplayer started, kB"), per phase: the robot's odometry messages
sent, its FUSED_POSE received, the latency from an odometry message's arrival to its pose's arrival (p50/p99/max), the RSS at the
phase's end and its peak; and the daemon's final counters (sources refused and evicted, loops dropped).
"""
import json
import math
import sys

from hostile_input import ident
from lcmlog import read_log, write_event
from sextant import fused_pose_t, loop_closure_t, odometry_t, status_t

RATE_HZ = 50
PHASES = [("quiet", 0.0, 20.0), ("names", 20.0, 80.0), ("loops", 80.0, 130.0), ("after", 130.0, 160.0)]
DURATION = PHASES[-1][2]
NAMES = 60_000
LOOPS = 100_000


COV6 = ident(6, 1e-4)
ZERO6 = ident(6, 0.0)
INC6 = ident(6, 1e-6)
INFO6 = ident(6, 100.0)


def odometry(utime, sender, seq, source, x, y, yaw):
    m = odometry_t()
    m.utime, m.sender, m.seq, m.source, m.planar = utime, sender, seq, source, True
    m.position = [x, y, 0.0]
    m.orientation = [math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]
    m.covariance, m.increment_covariance, m.twist_covariance = COV6, INC6, ZERO6
    m.linear_velocity = m.angular_velocity = [0.0] * 3
    return m.encode()


def loop(utime, seq, source, utime_from, utime_to):
    lc = loop_closure_t()
    lc.utime, lc.sender, lc.seq, lc.source, lc.matcher = utime, "flood-matcher", seq, source, "icp"
    lc.utime_from, lc.utime_to = utime_from, utime_to
    lc.position, lc.orientation, lc.information = [0.5, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], INFO6
    return lc.encode()


def make(path, start, flood=True):
    events = []
    # The robot: 1 m/s on a circle of radius 10 m.
    n = int(DURATION * RATE_HZ)
    for k in range(n):
        t = start + k * 1_000_000 // RATE_HZ
        a = k / RATE_HZ / 10.0
        events.append((t, "ODOMETRY", odometry(t, "robot-driver", k, "robot", 10 * math.sin(a), 10 - 10 * math.cos(a), a)))
    if not flood:
        names, loops = 0, 0
    else:
        names, loops = NAMES, LOOPS
    # The names: each sends twice.
    t0, t1 = start + 20_000_000, start + 80_000_000
    step = (t1 - t0) // (2 * NAMES)
    for i in range(names):
        for j in range(2):
            t = t0 + (2 * i + j) * step
            events.append((t + 1, "ODOMETRY", odometry(t, "flood-names", 2 * i + j, f"flood{i}", 0.0, 0.0, 0.0)))
    # The loops.
    t0, t1 = start + 80_000_000, start + 130_000_000
    step = (t1 - t0) // LOOPS
    for i in range(loops):
        t = t0 + i * step
        kind = i % 3
        if kind == 0:    # ahead of the robot's odometry by more than the run: waits until dropped
            src, fr, to = "robot", start + 1_000_000_000 + i, start + 2_000_000_000 + i
        elif kind == 1:  # before the robot's first message
            src, fr, to = "robot", start - 2_000_000_000 - i, start - 1_000_000_000 - i
        else:            # a body that never sent odometry
            src, fr, to = f"ghost{i}", t - 1_000_000, t - 500_000
        events.append((t + 2, "LOOP_CLOSURES", loop(t, i, src, fr, to)))
    events.sort(key=lambda e: e[0])
    with open(path, "wb") as f:
        for i, (t, c, b) in enumerate(events):
            write_event(f, i, t, c, b)


def pct(v, q):
    if not v:
        return None
    s = sorted(v)
    return s[min(len(s) - 1, max(0, math.ceil(q * len(s)) - 1))]  # nearest rank


def summarize(bus, rss_path, json_out=None):
    odo_at, pose_at, statuses = {}, {}, []
    for ts, c, b in read_log(bus):
        if c == "ODOMETRY":
            m = odometry_t.decode(b)
            if m.source == "robot":
                odo_at[m.utime] = ts
        elif c == "FUSED_POSE":
            m = fused_pose_t.decode(b)
            if m.source == "robot":
                pose_at.setdefault(m.utime, ts)
        elif c == "SEXTANT_STATUS":
            statuses.append(b)
    start = min(odo_at)
    # The RSS samples: microseconds since lcm-logplayer started (the robot's first message), kB.
    rss = [(int(s) / 1e6, int(kb)) for s, kb in (line.split() for line in open(rss_path) if line.strip())]
    out = {"phases": []}
    for name, a, b in PHASES:
        lo, hi = start + a * 1e6, start + b * 1e6
        on_bus = [u for u in odo_at if lo <= u < hi]
        lat = [(pose_at[u] - odo_at[u]) / 1000.0 for u in on_bus if u in pose_at]
        in_phase = [kb for s, kb in rss if a <= s < b]
        out["phases"].append({
            "phase": name, "robot_odometry_sent": int((b - a) * RATE_HZ), "robot_odometry_on_bus": len(on_bus),
            "robot_poses": sum(1 for u in pose_at if lo <= u < hi),
            "latency_ms_p50": pct(lat, 0.5), "latency_ms_p99": pct(lat, 0.99), "latency_ms_max": max(lat, default=None),
            "rss_mb_end": in_phase[-1] / 1024 if in_phase else None,
            "rss_mb_peak": max(in_phase) / 1024 if in_phase else None})
    final = status_t.decode(statuses[-1])
    out["channels"] = {c.channel: {"received": c.received, "decoded": c.decoded, "lost": c.lost,
                                   "reasons": dict(zip(c.reasons, c.reason_counts))}
                       for c in final.channels if c.channel in ("ODOMETRY", "LOOP_CLOSURES")}
    out["stages"] = {s.name: {"processed": s.processed, "dropped": s.dropped, "latency_ms_p50": s.latency_ms_p50,
                              "latency_ms_max": s.latency_ms_max, "last_failure": s.last_failure,
                              **dict(zip(s.counter_names, s.counter_values))} for s in final.stages}
    f = lambda v: "-" if v is None else f"{v:.1f}"
    print(f"{'phase':8} {'robot sent':>10} {'on bus':>7} {'poses':>6} {'p50 ms':>7} {'p99 ms':>7} {'max ms':>7} "
          f"{'RSS end MB':>10} {'RSS peak MB':>11}")
    for p in out["phases"]:
        print(f"{p['phase']:8} {p['robot_odometry_sent']:10d} {p['robot_odometry_on_bus']:7d} {p['robot_poses']:6d} "
              f"{f(p['latency_ms_p50']):>7} {f(p['latency_ms_p99']):>7} {f(p['latency_ms_max']):>7} "
              f"{f(p['rss_mb_end']):>10} {f(p['rss_mb_peak']):>11}")
    for name, c in out["channels"].items():
        print(f"{name}: {c}")
    for name, s in out["stages"].items():
        print(f"stage {name}: {s}")
    if json_out:
        with open(json_out, "w") as fo:
            json.dump(out, fo, indent=1)


if __name__ == "__main__":
    if sys.argv[1] == "make":
        make(sys.argv[2], int(sys.argv[3]), flood=len(sys.argv) < 5 or sys.argv[4] != "robot-only")
    else:
        summarize(sys.argv[2], sys.argv[3], sys.argv[4] if len(sys.argv) > 4 else None)
