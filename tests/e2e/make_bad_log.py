"""Writes an LCM log mixing valid odometry with every kind of bad input, and returns the expected counts.

Usage: make_bad_log.py OUT.lcm EXPECTED.json [--flood-seconds S]
Valid odometry runs at 100 Hz for 4 s; then a flood at 10x that rate (1 kHz) follows for --flood-seconds.
"""
import json
import math
import sys

from lcmlog import write_event
from sextant import odometry_t, landmarks_t, bearing_scan_t, bearing_detection_t

T0 = 1_700_000_000_000_000


def odometry(utime, x, seq):
    m = odometry_t()
    m.utime = utime
    m.sender = "bad-input-test"
    m.seq = seq
    m.source = "robot"
    m.planar = True
    m.position = [x, 0.0, 0.0]
    m.orientation = [1.0, 0.0, 0.0, 0.0]
    cov = [0.0] * 36
    cov[0] = cov[7] = 0.01
    cov[35] = 0.001
    m.covariance = cov
    m.has_increment_covariance = True
    inc = [0.0] * 36
    inc[0] = inc[7] = 1e-4
    inc[35] = 1e-5
    m.increment_covariance = inc
    m.has_twist = False
    m.linear_velocity = [0.0] * 3
    m.angular_velocity = [0.0] * 3
    m.twist_covariance = [0.0] * 36
    return m


def main():
    out, expected_path = sys.argv[1], sys.argv[2]
    flood_s = float(sys.argv[sys.argv.index("--flood-seconds") + 1]) if "--flood-seconds" in sys.argv else 2.0
    expect = {"valid": 0, "reasons": {}, "flood": 0}

    def bad(reason):
        expect["reasons"][reason] = expect["reasons"].get(reason, 0) + 1

    events = []  # (log timestamp, channel, bytes)
    seq = 0
    for k in range(400):  # 4 s at 100 Hz
        t = T0 + k * 10_000
        events.append((t, "ODOMETRY", odometry(t, 0.01 * k, seq).encode()))
        seq += 1
        expect["valid"] += 1
        j = k % 40
        tb = t + 5_000  # between two valid messages
        if j == 1:
            events.append((tb, "ODOMETRY", bytes([0x5A] * 37)))  # garbage
            bad("fingerprint")
        elif j == 2:
            events.append((tb, "ODOMETRY", bytes(5)))  # too short for a fingerprint
            bad("decode")
        elif j == 3:
            lm = landmarks_t()
            lm.utime = tb
            lm.sender = "x"
            lm.source = "robot"
            lm.sensor_position = [0.0] * 3
            lm.sensor_orientation = [1.0, 0.0, 0.0, 0.0]
            lm.num_observations = 0
            lm.observations = []
            events.append((tb, "ODOMETRY", lm.encode()))  # a valid message of the wrong type
            bad("fingerprint")
        elif j == 4:
            m = odometry(tb, 0.01 * k, seq)
            m.position = [float("nan"), 0.0, 0.0]
            events.append((tb, "ODOMETRY", m.encode()))
            bad("non_finite")
        elif j == 5:
            m = odometry(tb, 0.01 * k, seq)
            m.covariance = [0.0] * 36  # not positive definite
            events.append((tb, "ODOMETRY", m.encode()))
            bad("covariance")
        elif j == 6:
            m = odometry(t, 0.01 * k, seq)  # duplicate utime of the valid message just sent
            events.append((tb, "ODOMETRY", m.encode()))
            bad("time_order")
        elif j == 7:
            m = odometry(t - 20_000, 0.0, seq)  # backwards
            events.append((tb, "ODOMETRY", m.encode()))
            bad("time_order")
        elif j == 8:
            m = odometry(tb, 0.01 * k, seq)
            m.orientation = [2.0, 0.0, 0.0, 0.0]
            events.append((tb, "ODOMETRY", m.encode()))
            bad("quaternion")
        elif j == 9:
            s = bearing_scan_t()
            s.utime = tb
            s.sender = "x"
            s.sensor_id = 1
            s.sensor_position = [0.0] * 3
            s.scan_id = k
            s.num_detections = 5000  # over the limit
            d = bearing_detection_t()
            d.azimuth = d.elevation = 0.0
            d.sigma_azimuth = d.sigma_elevation = 0.01
            s.detections = [d] * 5000
            events.append((tb, "BEARINGS", s.encode()))
            bad("too_large")
        elif j == 10:
            m = odometry(tb, 0.01 * k, seq)
            m.covariance = [1e-2 if i in (0, 7, 35) else 0.0 for i in range(36)]
            m.covariance[1] = 5.0  # asymmetric
            events.append((tb, "ODOMETRY", m.encode()))
            bad("covariance")
    # The flood: 10x the normal rate.
    t_flood = T0 + 400 * 10_000
    n_flood = int(flood_s * 1000)
    for k in range(n_flood):
        t = t_flood + k * 1_000
        events.append((t, "ODOMETRY", odometry(t, 4.0 + 0.001 * k, seq).encode()))
        seq += 1
    expect["flood"] = n_flood
    expect["bearings_rejected"] = expect["reasons"].pop("too_large")
    with open(out, "wb") as f:
        for i, (ts, ch, data) in enumerate(events):
            write_event(f, i, ts, ch, data)
    with open(expected_path, "w") as f:
        json.dump(expect, f)


if __name__ == "__main__":
    main()
