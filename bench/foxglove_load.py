"""Writes the bridge benchmark's load as an LCM log (bench/foxglove.sh): BODIES bodies each publishing fused poses
at RATE Hz (FUSED_POSE, estimator "ekf", moving on circles, each in its own map frame), each body's TRAJECTORY at 1 Hz (an UPDATE carrying the
new keyframe, a full SNAPSHOT every 10 s) and SEXTANT_STATUS at 1 Hz, for SECONDS seconds; `sextant replay --realtime`
plays it at the pace of its utimes.

Usage: foxglove_load.py OUT.lcm [--bodies 10] [--rate 100] [--seconds 30]
"""
import argparse
import math
import sys

from lcmlog import write_event  # tests/e2e/lcmlog.py
from sextant.fused_pose_t import fused_pose_t
from sextant.keyframe_t import keyframe_t
from sextant.stage_status_t import stage_status_t
from sextant.status_t import status_t
from sextant.trajectory_t import trajectory_t

T0 = 1_700_000_000_000_000


def pose(body, t):
    a = 0.2 * t + body
    return [10 * body + 5 * math.cos(a), 5 * math.sin(a), 0.0], [math.cos(a / 2 + 0.8), 0.0, 0.0, math.sin(a / 2 + 0.8)]


def fused(body, i, utime, t):
    m = fused_pose_t()
    m.utime, m.sender, m.seq, m.source, m.estimator, m.planar = utime, "bench", i, f"robot{body}", "ekf", True
    m.frame = f"robot{body}"  # each body in its own map frame, as sextantd's filters publish it
    m.position, m.orientation = pose(body, t)
    m.covariance = [0.01 if k % 7 == 0 else 0.0 for k in range(36)]
    return m


def trajectory(body, seq, utime, keyframes, snapshot):
    m = trajectory_t()
    m.utime, m.sender, m.seq, m.source, m.estimator = utime, "bench", seq, f"robot{body}", "graph"
    m.frame = f"robot{body}"  # not joined: ten map frames
    m.kind = trajectory_t.SNAPSHOT if snapshot else trajectory_t.UPDATE
    m.num_chunks, m.range_first, m.range_last = 1, 0, len(keyframes) - 1
    m.total_keyframes = len(keyframes)
    m.keyframes = keyframes if snapshot else keyframes[-1:]
    m.num_keyframes = len(m.keyframes)
    return m


def status(seq, utime, uptime):
    m = status_t()
    m.utime, m.sender, m.seq, m.version, m.uptime_s = utime, "bench", seq, "bench", uptime
    for name in ("dead_reckoning", "ekf", "graph"):
        s = stage_status_t()
        s.name, s.queue_capacity, s.processed = name, 1024, seq * 1000
        s.latency_ms_p50, s.latency_ms_p90, s.latency_ms_p99, s.latency_ms_max = 0.1, 0.2, 0.5, 1.0
        m.stages.append(s)
    m.num_stages = len(m.stages)
    return m


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--bodies", type=int, default=10)
    p.add_argument("--rate", type=float, default=100)
    p.add_argument("--seconds", type=float, default=30)
    a = p.parse_args()
    n = 0
    keyframes = {b: [] for b in range(a.bodies)}
    with open(a.out, "wb") as f:
        def put(channel, utime, msg):
            nonlocal n
            write_event(f, n, utime, channel, msg.encode())
            n += 1
        for i in range(int(a.seconds * a.rate)):
            t = i / a.rate
            utime = T0 + round(t * 1e6)
            for b in range(a.bodies):
                put("FUSED_POSE", utime, fused(b, i, utime, t))
            if i % int(a.rate) == 0:
                sec = i // int(a.rate)
                for b in range(a.bodies):
                    k = keyframe_t()
                    k.id, k.utime = sec, utime
                    k.position, k.orientation = pose(b, t)
                    keyframes[b].append(k)
                    put("TRAJECTORY", utime, trajectory(b, sec, utime, keyframes[b], sec % 10 == 9))
                put("SEXTANT_STATUS", utime, status(sec, utime, t))
    print(f"{a.out}: {n} events, {a.bodies} bodies at {a.rate:g} Hz for {a.seconds:g} s", file=sys.stderr)


if __name__ == "__main__":
    main()
