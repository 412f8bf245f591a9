"""The lag that FUSED_POSE carries after a stall (stall_lag.sh).

make OUT.lcm BASE_US: one robot's odometry at 10 Hz for 10 s, utime BASE_US + 100 ms x k, each event stamped with
its utime (lcm-logplayer sends event k 100 ms x k after it starts, so a message's utime is its send time less the
player's start-up delay).
check BUS.lcm STOP_US CONT_US: the FUSED_POSE of that robot on the bus, while sextantd was stopped (SIGSTOP) from
STOP_US to CONT_US (wall clock, us).  Every pose carries lag_us = the daemon's wall clock when it published it minus
its utime: each pose of an odometry message sent during the stall (published after SIGCONT) says it is at least as
late as it was (CONT_US - utime), the first of them the stall (less the time to the first message sent in it); every pose agrees within 0.5 s with the
lateness lcm-logger saw (its receive time of the pose minus the pose's utime); and the poses well before the stall
and well after the backlog say they are not late (under 0.5 s more than the player's start-up delay).
"""
import statistics
import sys

from hostile_input import odometry
from lcmlog import read_log, write_event
from sextant import fused_pose_t, odometry_t

RATE_HZ = 10  # the backlog is published in one burst: at 50 Hz lcm-logger lost a hundred of the 150 poses
SECONDS = 10


def make(path, base):
    with open(path, "wb") as f:
        for k in range(RATE_HZ * SECONDS):
            utime = base + k * 1_000_000 // RATE_HZ
            write_event(f, k, utime, "ODOMETRY", odometry(utime, k, 0.1 * k).encode())


def check(bus, stop, cont):
    poses, sent = [], []
    for ts, channel, data in read_log(bus):
        if channel == "FUSED_POSE":
            m = fused_pose_t.decode(data)
            if m.source == "robot":
                poses.append((ts, m))
        elif channel == "ODOMETRY":
            sent.append(ts - odometry_t.decode(data).utime)
    startup = statistics.median(sent)  # lcm-logger's receive time minus utime: the player's start-up delay
    stall = cont - stop
    print(f"{len(poses)} poses; player start-up delay {startup / 1e3:.1f} ms; stall {stall / 1e6:.3f} s")
    assert len(poses) >= RATE_HZ * SECONDS * 0.7, len(poses)  # lcm-logger loses a few of the burst (below)
    stalled = [(ts, m) for ts, m in poses if stop <= m.utime + startup and m.utime + startup < cont]
    # lcm-logger may lose some of the burst the backlog is published in (the daemon published them all)
    assert len(stalled) >= RATE_HZ * stall / 1e6 * 0.5, f"{len(stalled)} poses of the stall"
    for ts, m in stalled:
        assert m.lag_us >= cont - m.utime, f"pose {m.utime}: lag {m.lag_us} us, published after {cont - m.utime} us"
    worst = max(m.lag_us for _, m in stalled)
    period = 1_000_000 // RATE_HZ  # the first message of the stall was sent at most this long after it began
    assert worst >= stall - period, f"largest lag {worst} us, stall {stall} us"
    for ts, m in poses:
        assert abs(m.lag_us - (ts - m.utime)) < 500_000, f"pose {m.utime}: lag {m.lag_us} us, seen {ts - m.utime} us"
    normal = [m for _, m in poses if m.utime + startup < stop - 500_000 or m.utime + startup > cont + 1_500_000]
    assert len(normal) >= RATE_HZ * 2, f"{len(normal)} poses outside the stall"
    for m in normal:
        assert m.lag_us < startup + 500_000, f"pose {m.utime} outside the stall: lag {m.lag_us} us"
    print(f"lag after the stall: largest {worst / 1e6:.3f} s over {len(stalled)} poses; outside it at most "
          f"{max(m.lag_us for m in normal) / 1e6:.3f} s over {len(normal)} poses")


if __name__ == "__main__":
    if sys.argv[1] == "make":
        make(sys.argv[2], int(sys.argv[3]))
    else:
        check(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]))
