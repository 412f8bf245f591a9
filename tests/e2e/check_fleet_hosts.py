"""Checks a fleet of daemons, one per robot on its own test host, against one daemon fed every robot's data.

Usage: check_fleet_hosts.py [--restarted HOST] SINGLE_OUT.lcm TOLERANCE_M HOST=BUS.lcm ...
SINGLE_OUT.lcm is the output log of `sextant replay` of the whole fleet (TRAJECTORY); each BUS.lcm is what a logger on
that host recorded of its daemon's outputs (PREFIX_TRAJECTORY of the daemon named HOST, its prefix inferred).  For
every host and every robot: the daemon's final trajectory of the robot (its own view, TRAJECTORY rebuilt) holds the
same keyframes as the single daemon's (ids; none lost) within TOLERANCE_M RMS over positions, and all robots end in
one map frame.  With --restarted HOST (a daemon killed and restarted on its state directory): its graph stage's
last status shows it took back what it had sent since its last save (fleet_tail_adopted > 0), and no daemon's shows
a stream rewound (fleet_in_owner_rewound = 0)."""
import math
import sys

from lcmlog import read_log, rebuild_trajectories
from sextant import status_t, trajectory_t


def trajectories(path, channel_suffix, sender=None):
    msgs = [trajectory_t.decode(b) for _, c, b in read_log(path) if c.endswith(channel_suffix)]
    if sender is not None:
        msgs = [m for m in msgs if m.sender == sender]
    frames = {}
    for m in msgs:
        frames[m.source] = m.frame
    return rebuild_trajectories(msgs), frames


def graph_counters(path, sender):
    """The graph stage's counters in the last status of `sender` in the bus log at `path`."""
    counters = {}
    for _, c, b in read_log(path):
        if c.endswith("SEXTANT_STATUS"):
            status = status_t.decode(b)
            if status.sender == sender:
                for st in status.stages:
                    if st.name == "graph":
                        counters = dict(zip(st.counter_names, st.counter_values))
    return counters


def rms(a, b):
    pa = {k.id: k.position for k in a}
    pb = {k.id: k.position for k in b}
    common = sorted(set(pa) & set(pb))
    if not common:
        return math.inf, 0
    s = sum(sum((x - y) ** 2 for x, y in zip(pa[i], pb[i])) for i in common)
    return math.sqrt(s / len(common)), len(common)


def main():
    args = sys.argv[1:]
    restarted = None
    if args[0] == "--restarted":
        restarted, args = args[1], args[2:]
    single_path, tolerance = args[0], float(args[1])
    hosts = dict(a.split("=", 1) for a in args[2:])
    single, single_frames = trajectories(single_path, "TRAJECTORY")
    robots = single.sources()
    failures = []
    if len(set(single_frames.values())) != 1:
        failures.append(f"the single daemon ends in {len(set(single_frames.values()))} frames")
    for host, path in sorted(hosts.items()):
        view, frames = trajectories(path, "TRAJECTORY", sender=host)
        if len(set(frames.values())) != 1 or set(frames) != set(robots):
            failures.append(f"{host}: robots {sorted(frames)} in frames {sorted(set(frames.values()))}")
        for robot in robots:
            mine, ref = view.keyframes(robot), single.keyframes(robot)
            err, n = rms(mine, ref)
            lost = len({k.id for k in ref} - {k.id for k in mine})
            print(f"{host}: {robot}: {len(mine)} keyframes (single daemon {len(ref)}), {n} in common, "
                  f"RMS {err * 100:.2f} cm, {lost} of the single daemon's missing")
            if err > tolerance or lost > 0:
                failures.append(f"{host}: {robot}: RMS {err:.4f} m, {lost} keyframes missing")
        counters = graph_counters(path, host)
        rewound, adopted = counters.get("fleet_in_owner_rewound"), counters.get("fleet_tail_adopted")
        print(f"{host}: fleet_in_owner_rewound {rewound}, fleet_tail_adopted {adopted}")
        if rewound != 0:
            failures.append(f"{host}: fleet_in_owner_rewound {rewound}")
        if host == restarted and not adopted:
            failures.append(f"{host}: restarted, took nothing back (fleet_tail_adopted {adopted})")
    if failures:
        sys.exit("\n".join(failures))
    print("fleet hosts: every daemon holds the single daemon's map")


if __name__ == "__main__":
    main()
