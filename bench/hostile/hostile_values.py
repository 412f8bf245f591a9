"""The "hostile values" cases of bench/hostile/hostile_values.sh: each one mutates one valid message of a simulated
planar run (or adds a few), and `check` reads what `sextant replay --out-log` published.

  python3 hostile_values.py make CASE CLEAN.lcm OUT.lcm
  python3 hostile_values.py check PUBLISHED.lcm   -> one JSON line: poses, non-finite, negative variance, max |x|

Cases (all messages decode and every number is finite):
  position_1e308       one odometry message at x = 1e308
  increment_cov_1e300  one odometry message whose increment covariance is 1e300 on its diagonal
  planar_roll_180      one planar odometry message rolled 180 degrees (quaternion [0, 1, 0, 0])
  range_1e308          one sighting of a known landmark at range 1e308
  unknown_4096_x5      five landmarks_t of 4096 sightings without id, 0.1 s apart
  second_sender        a second sender on the same source, 100 m away, every message
"""
import json
import math
import os
import random
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tests", "e2e"))
from lcmlog import read_log, write_event  # noqa: E402
from sextant import fused_pose_t, landmarks_t, odometry_t  # noqa: E402


def mutate(case, events):
    out, odo, lmk = [], 0, 0
    rng = random.Random(1)
    for ts, ch, data in events:
        if ch == "ODOMETRY":
            odo += 1
            m = odometry_t.decode(data)
            if odo == 1000 and case == "position_1e308":
                m.position = [1e308, 0.0, 0.0]
            elif odo == 1000 and case == "increment_cov_1e300":
                m.has_increment_covariance = True
                m.increment_covariance = [1e300 if i % 7 == 0 else 0.0 for i in range(36)]
            elif odo == 1000 and case == "planar_roll_180":
                m.orientation = [0.0, 1.0, 0.0, 0.0]
            elif case == "second_sender":
                out.append((ts, ch, data))
                m.sender = "impostor"
                m.utime += 5000  # between two of the robot's messages (50 Hz)
                m.position = [m.position[0] + 100.0, m.position[1], m.position[2]]
                ts += 5000
            data = m.encode()
        elif ch == "LANDMARKS":
            lmk += 1
            m = landmarks_t.decode(data)
            if case == "range_1e308" and lmk == 100 and m.num_observations > 0:
                m.observations[0].range = 1e308
            elif case == "unknown_4096_x5" and 100 <= lmk < 105 and m.num_observations > 0:
                one = m.observations[0]
                obs = []
                for _ in range(4096):
                    o = landmarks_t.decode(m.encode()).observations[0]
                    o.id = -1
                    o.range = 1 + 10 * rng.random()
                    o.azimuth = rng.uniform(-3, 3)
                    o.covariance = list(one.covariance)
                    obs.append(o)
                m.observations = obs
                m.num_observations = 4096
            data = m.encode()
        out.append((ts, ch, data))
    return out


def make(case, clean, path):
    events = mutate(case, list(read_log(clean)))
    with open(path, "wb") as f:
        for i, (ts, ch, data) in enumerate(events):
            write_event(f, i, ts, ch, data)


def check(path):
    poses = bad = negative = 0
    biggest = 0.0
    last = {}
    for _, ch, data in read_log(path):
        if not ch.startswith("FUSED_POSE"):
            continue
        m = fused_pose_t.decode(data)
        poses += 1
        values = list(m.position) + list(m.orientation) + list(m.covariance)
        if not all(math.isfinite(v) for v in values):
            bad += 1
            continue
        if any(m.covariance[7 * i] < 0 for i in range(6)):
            negative += 1
        biggest = max(biggest, max(abs(v) for v in m.position))
        last[ch] = [round(m.position[0], 3), round(m.position[1], 3)]
    print(json.dumps({"poses": poses, "non_finite": bad, "negative_variance": negative,
                      "max_abs_position": float(f"{biggest:.4g}"), "last_xy": last}))


if __name__ == "__main__":
    if sys.argv[1] == "make":
        make(sys.argv[2], sys.argv[3], sys.argv[4])
    else:
        check(sys.argv[2])
