"""Checks of tests/e2e/crash_resume.sh: sim.lcm (played, with the ground truth), a.lcm (the bus of the uninterrupted
run), b.lcm (the bus of the run killed and resumed) and run B's two daemon logs.  Errors against the truth:
  - graph: RMS position error of the final keyframes, rebuilt from TRAJECTORY as a subscriber would;
  - ekf: mean position error of FUSED_POSE (the primary estimator, the EKF) after the restart's time.
Run B must be within 10 % of run A on both (plus 5 mm for the EKF, whose error is a few centimetres)."""
import bisect
import math
import sys

from lcmlog import read_log, rebuild_trajectories
from sextant import fused_pose_t, status_t, trajectory_t, truth_t


def graph_counters(bus):
    counters = None
    for c, b in bus:
        if c == "SEXTANT_STATUS":
            for st in status_t.decode(b).stages:
                if st.name == "graph":
                    counters = dict(zip(st.counter_names, st.counter_values))
    return counters or {}


def main():
    sim_path, a_path, b_path = sys.argv[1:4]
    sim = list(read_log(sim_path))
    truth = sorted((t.utime, t.position) for t in (truth_t.decode(b) for _, c, b in sim if c == "GROUND_TRUTH")
                   if t.kind == "robot")
    times = [t for t, _ in truth]

    def truth_at(utime):
        i = bisect.bisect_left(times, utime)
        best = min((j for j in (i - 1, i) if 0 <= j < len(truth)), key=lambda j: abs(times[j] - utime))
        return truth[best][1]

    runs = {}
    for name, path in (("A", a_path), ("B", b_path)):
        bus = [(c, b) for _, c, b in read_log(path)]
        trajectories = [trajectory_t.decode(b) for c, b in bus if c == "TRAJECTORY"]
        keyframes = rebuild_trajectories(trajectories).keyframes(trajectories[-1].source)
        graph = math.sqrt(sum(math.dist(k.position[:2], truth_at(k.utime)[:2]) ** 2 for k in keyframes) / len(keyframes))
        fused = [fused_pose_t.decode(b) for c, b in bus if c == "FUSED_POSE"]
        runs[name] = dict(keyframes=keyframes, graph=graph, fused=fused, counters=graph_counters(bus))

    # The restart: the first FUSED_POSE of run B after the largest step between two consecutive ones (the gap).
    fb = runs["B"]["fused"]
    gaps = [(b.utime - a.utime, b.utime) for a, b in zip(fb, fb[1:])]
    gap, restart = max(gaps)
    errors = []
    if gap < 0.5e6:  # down CRASH_RESUME_DOWN_S (0.25 s) at 4x: at least 1 s of data; the odometry comes at 50 Hz
        errors.append(f"no gap in run B's FUSED_POSE (largest {gap} us): the daemon was not down")
    for name in ("A", "B"):
        after = [f for f in runs[name]["fused"] if f.utime >= restart]
        runs[name]["ekf"] = sum(math.dist(f.position[:2], truth_at(f.utime)[:2]) for f in after) / max(1, len(after))
        runs[name]["ekf_poses"] = len(after)
        c = runs[name]["counters"]
        print(f"run {name}: {len(runs[name]['keyframes'])} keyframes, graph RMS {runs[name]['graph']:.4f} m; "
              f"EKF mean error after t={restart / 1e6:.1f} s {runs[name]['ekf']:.4f} m over {len(after)} poses; "
              f"loops accepted {c.get('loops_accepted')}, unmatched {c.get('loops_unmatched')}, "
              f"rejected {c.get('loops_rejected')}")
    print(f"restart gap in run B: {gap / 1e6:.2f} s of data at t={restart / 1e6:.1f} s")
    a, b = runs["A"], runs["B"]
    if not b["graph"] <= 1.10 * a["graph"]:
        errors.append(f"graph error after the crash {b['graph']:.4f} m > 1.1 x uninterrupted {a['graph']:.4f} m")
    if not b["ekf"] <= 1.10 * a["ekf"] + 0.005:
        errors.append(f"EKF error after the crash {b['ekf']:.4f} m > 1.1 x uninterrupted {a['ekf']:.4f} m + 5 mm")
    ua, ub = a["counters"].get("loops_unmatched", 0), b["counters"].get("loops_unmatched", 0)
    if ub > ua + 5:
        errors.append(f"loops unmatched after the crash: {ub}, uninterrupted {ua} (pre-crash keyframes lost?)")
    if b["counters"].get("loops_accepted", 0) < 0.8 * a["counters"].get("loops_accepted", 0):
        errors.append("far fewer loops accepted after the crash")
    if errors:
        print("FAILED:\n  " + "\n  ".join(errors))
        sys.exit(1)


if __name__ == "__main__":
    main()
