"""Checks of tests/e2e/graph_bus.sh: sim.lcm (what was played, with the ground truth), bus.lcm (everything on the bus,
recorded by lcm-logger) and the matcher's --json counts."""
import bisect
import json
import math
import sys

from lcmlog import read_log, rebuild_trajectories
from sextant import fused_pose_t, match_request_t, loop_closure_t, odometry_t, status_t, trajectory_t, truth_t


def main():
    sim_path, bus_path, counts_path = sys.argv[1:4]
    sim = list(read_log(sim_path))
    bus = [(c, b) for _, c, b in read_log(bus_path)]
    errors = []
    odometry = [odometry_t.decode(b) for _, c, b in sim if c == "ODOMETRY"]
    truth = sorted((t.utime, t.position) for t in (truth_t.decode(b) for _, c, b in sim if c == "GROUND_TRUTH")
                   if t.kind == "robot")
    truth_times = [t for t, _ in truth]

    def truth_at(utime):
        i = bisect.bisect_left(truth_times, utime)
        best = min((j for j in (i - 1, i) if 0 <= j < len(truth)), key=lambda j: abs(truth_times[j] - utime))
        return truth[best][1]

    requests = [match_request_t.decode(b) for c, b in bus if c == "MATCH_REQUESTS"]
    answers = [loop_closure_t.decode(b) for c, b in bus if c == "LOOP_CLOSURES"]
    counts = json.load(open(counts_path))
    if len(requests) < 50:
        errors.append(f"only {len(requests)} MATCH_REQUESTS")
    if counts.get("answered", 0) + counts.get("wrong", 0) < len(requests) // 2:
        errors.append(f"the matcher answered too few of {len(requests)} requests: {counts}")
    if counts.get("wrong", 0) == 0:
        errors.append("no wrong answers were drawn (the test needs some)")

    fused = [fused_pose_t.decode(b) for c, b in bus if c == "FUSED_POSE"]
    dead = [fused_pose_t.decode(b) for c, b in bus if c == "FUSED_POSE_DEAD_RECKONING"]
    if any(f.estimator != "graph" for f in fused):
        errors.append("FUSED_POSE is not the graph's")
    if len(fused) < 0.95 * len(odometry):  # lcm-logger itself may lose a few datagrams
        errors.append(f"{len(fused)} FUSED_POSE for {len(odometry)} odometry messages")
    if any(b.utime <= a.utime for a, b in zip(fused, fused[1:])):
        errors.append("FUSED_POSE utimes are not strictly increasing")

    raw_trajectories = [b for c, b in bus if c == "TRAJECTORY"]
    trajectories = [trajectory_t.decode(b) for b in raw_trajectories]
    if not trajectories:
        errors.append("no TRAJECTORY")
    else:
        if max(len(b) for b in raw_trajectories) > 64 * 1024:
            errors.append(f"a TRAJECTORY message of {max(len(b) for b in raw_trajectories)} bytes (over 64 KB)")
        # The whole trajectory, rebuilt from the updates and snapshot chunks as any subscriber would.
        keyframes = rebuild_trajectories(trajectories).keyframes(trajectories[-1].source)
        if len(keyframes) != trajectories[-1].total_keyframes:
            errors.append(f"rebuilt {len(keyframes)} keyframes, the last TRAJECTORY says {trajectories[-1].total_keyframes}")
        dr = {d.utime: d.position for d in dead}
        err_graph, err_dr = [], []
        for k in keyframes:
            t = truth_at(k.utime)
            err_graph.append(math.dist(k.position[:2], t[:2]) ** 2)
            if k.utime in dr:
                err_dr.append(math.dist(dr[k.utime][:2], t[:2]) ** 2)
        rms_graph = math.sqrt(sum(err_graph) / len(err_graph))
        rms_dr = math.sqrt(sum(err_dr) / max(1, len(err_dr)))
        print(f"{len(keyframes)} keyframes: RMS error {rms_graph:.3f} m, dead reckoning at the same times {rms_dr:.3f} m")
        if not rms_graph < 0.5 * rms_dr:
            errors.append(f"the optimized keyframes ({rms_graph:.3f} m) are not far better than dead reckoning ({rms_dr:.3f} m)")

    statuses = [status_t.decode(b) for c, b in bus if c == "SEXTANT_STATUS"]
    graph = None
    for s in statuses:
        for st in s.stages:
            if st.name == "graph":
                graph = dict(zip(st.counter_names, st.counter_values))
    if graph is None:
        errors.append("no graph stage on SEXTANT_STATUS")
    else:
        print("graph counters:", graph)
        if graph.get("loops_accepted", 0) < counts.get("answered", 0) // 2:
            errors.append("fewer than half of the correct answers were accepted")
        if graph.get("keyframes", 0) < 20:
            errors.append("too few keyframes")
    print(f"{len(requests)} requests, matcher {counts}, {len(answers)} loop closures on the bus, "
          f"{len(fused)} FUSED_POSE, {len(trajectories)} TRAJECTORY")
    if errors:
        print("FAILED:\n  " + "\n  ".join(errors))
        sys.exit(1)


if __name__ == "__main__":
    main()
