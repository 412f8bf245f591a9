"""A hostile sender's log for sextantd, and the check of what the daemon made of it (hostile_input.sh).

make OUT.lcm: one robot's odometry at 50 Hz ("robot", 300 messages, sequence numbers with 10 gaps) and one bearing
sensor's scans (30), interleaved with what used to kill or cut off the daemon: a 20-byte odometry payload whose
sender has length 0 (lcm-gen threw std::length_error: exit 134), landmarks whose count is 0x7fffffff (bad_alloc)
and 20,000,000 (2 GB), zero- and negative-length strings in every input type, one odometry message dated 2100
and one at INT64_MAX (every later message of the body was rejected as "before the previous"), and a scan dated
2100 (it blocked its sensor's next 60 scans); and 1000 new body names, one message each (state per name grew
without bound: 60k names took 326 MB).
check BUS.lcm: the daemon's last SEXTANT_STATUS and its FUSED_POSE output on the bus.
"""
import struct
import sys

from lcmlog import read_log, write_event
from sextant import (bearing_detection_t, bearing_scan_t, fused_pose_t, landmark_observation_t, landmarks_t,
                     loop_closure_t, odometry_t, status_t)

T0 = 1_700_000_000_000_000
T2100 = 4_102_444_800_000_000
INT64_MAX = 2**63 - 1
ODOMETRY = 300
SCANS = 30
GAPS = 10
NAMES = 1000       # odometry of as many distinct bodies (one message each): beyond daemon.max_sources, refused
MAX_SOURCES = 256


def ident(n, s):
    return [s if i % (n + 1) == 0 else 0.0 for i in range(n * n)]


def odometry(utime, seq, x):
    m = odometry_t()
    m.utime, m.sender, m.seq, m.source, m.planar = utime, "robot-driver", seq, "robot", True
    m.position, m.orientation = [x, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]
    m.covariance = ident(6, 1e-4)
    m.increment_covariance = ident(6, 0.0)
    m.linear_velocity = m.angular_velocity = [0.0] * 3
    m.twist_covariance = ident(6, 0.0)
    return m


def scan(utime, seq):
    s = bearing_scan_t()
    s.utime, s.sender, s.seq, s.sensor_id, s.sensor_position, s.scan_id = utime, "sensor", seq, 1, [0.0, 0.0, 5.0], seq
    d = bearing_detection_t()
    d.azimuth, d.elevation, d.sigma_azimuth, d.sigma_elevation = 0.3, 0.1, 0.01, 0.01
    s.detections, s.num_detections = [d], 1
    return s


def landmarks(count_field):
    lm = landmarks_t()
    lm.utime, lm.sender, lm.seq, lm.source, lm.planar = T0, "x", 0, "robot", True
    lm.sensor_position, lm.sensor_orientation = [0.0] * 3, [1.0, 0.0, 0.0, 0.0]
    lm.observations, lm.num_observations = [], 0
    b = bytearray(lm.encode())
    b[-4:] = struct.pack(">i", count_field)
    return bytes(b) + bytes(112 - len(b)) if len(b) < 112 else bytes(b)


def with_string_length(msg_bytes, at, n):
    b = bytearray(msg_bytes)
    b[at:at + 4] = struct.pack(">i", n)
    return bytes(b)


def make(path):
    events = []
    hostile = []
    fp = odometry(T0, 0, 0.0).encode()[:8]
    hostile.append(("ODOMETRY", fp + struct.pack(">q", 1) + struct.pack(">i", 0)))        # 20 bytes
    hostile.append(("LANDMARKS", landmarks(0x7FFFFFFF)))
    hostile.append(("LANDMARKS", landmarks(20_000_000)))
    hostile.append(("BEARINGS", with_string_length(scan(T0, 0).encode(), 16, 0)))
    lc = loop_closure_t()
    lc.utime, lc.sender, lc.source, lc.matcher = T0, "m", "robot", "icp"
    lc.utime_from, lc.utime_to = T0, T0 + 1
    lc.position, lc.orientation, lc.information = [0.0] * 3, [1.0, 0.0, 0.0, 0.0], ident(6, 1.0)
    hostile.append(("LOOP_CLOSURES", with_string_length(lc.encode(), 16, -7)))
    seq = 0
    for k in range(ODOMETRY):
        t = T0 + (k + 1) * 20_000
        if k % 30 == 15:
            seq += 1  # a gap of one sequence number
        events.append((t, "ODOMETRY", odometry(t, seq, 0.01 * k).encode()))
        seq += 1
        if k == 10:
            events.append((t + 1, "ODOMETRY", odometry(T2100, seq, 0.0).encode()))
            seq += 1
        if k == 20:
            events.append((t + 1, "ODOMETRY", odometry(INT64_MAX, seq, 0.0).encode()))
            seq += 1
        if k < len(hostile):
            events.append((t + 2, hostile[k][0], hostile[k][1]))
        if 50 <= k < 50 + NAMES // 100:
            for n in range(100):
                m = odometry(t + 5 + n, 100 * (k - 50) + n, 0.0)
                m.sender, m.source = "namer", f"name{100 * (k - 50) + n}"
                events.append((t + 5 + n, "ODOMETRY", m.encode()))
        if k % 10 == 0:
            s = k // 10
            events.append((t + 3, "BEARINGS", scan(t, s).encode()))
            if s == 1:
                events.append((t + 4, "BEARINGS", scan(T2100, 100).encode()))
    with open(path, "wb") as f:
        for i, (t, c, b) in enumerate(events):
            write_event(f, i, t, c, b)


def check(bus):
    statuses = [status_t.decode(b) for _, c, b in read_log(bus) if c == "SEXTANT_STATUS"]
    fused = [fused_pose_t.decode(b) for _, c, b in read_log(bus) if c == "FUSED_POSE"]
    assert statuses, "no status message"
    final = statuses[-1]
    ch = {c.channel: c for c in final.channels}
    reasons = {name: dict(zip(c.reasons, c.reason_counts)) for name, c in ch.items()}
    errors = []
    odo, lm, br, lc = ch["ODOMETRY"], ch["LANDMARKS"], ch["BEARINGS"], ch["LOOP_CLOSURES"]
    sent_odometry = ODOMETRY + 3 + NAMES
    # What UDP lost on the way is counted too: lost = the 10 gaps + what never arrived of this sender's messages.
    never_arrived = sent_odometry - odo.received
    if odo.lost != GAPS + never_arrived:
        errors.append(f"ODOMETRY lost {odo.lost}, expected {GAPS} gaps + {never_arrived} not received")
    lost_by_sender = dict(zip(odo.lost_senders, odo.lost_counts))
    if sum(lost_by_sender.values()) != odo.lost or lost_by_sender.get("robot-driver", 0) < GAPS:
        errors.append(f"ODOMETRY lost by sender {lost_by_sender}: expected the {GAPS} gaps under robot-driver, "
                      f"summing to {odo.lost}")
    if reasons["ODOMETRY"].get("decode") != 1:
        errors.append(f"ODOMETRY decode rejections {reasons['ODOMETRY']}")
    if reasons["ODOMETRY"].get("time_future") != 2:
        errors.append(f"ODOMETRY time_future rejections {reasons['ODOMETRY']}")
    if "time_order" in reasons["ODOMETRY"]:
        errors.append(f"normal odometry refused after the future stamps: {reasons['ODOMETRY']}")
    refused_names = NAMES - (MAX_SOURCES - 2)  # the robot and the bearing sensor hold a place each
    if reasons["ODOMETRY"].get("too_many_sources") != refused_names:
        errors.append(f"too_many_sources {reasons['ODOMETRY'].get('too_many_sources')}, expected {refused_names}")
    if odo.decoded != odo.received - 3 - refused_names:
        errors.append(f"ODOMETRY decoded {odo.decoded} of {odo.received} (3 hostile, {refused_names} names refused)")
    if reasons["LANDMARKS"].get("too_large") != 2:
        errors.append(f"LANDMARKS rejections {reasons['LANDMARKS']}")
    if reasons["BEARINGS"].get("decode") != 1 or reasons["BEARINGS"].get("time_future") != 1:
        errors.append(f"BEARINGS rejections {reasons['BEARINGS']}")
    if br.decoded != br.received - 2:
        errors.append(f"BEARINGS decoded {br.decoded} of {br.received} (2 hostile)")
    if reasons["LOOP_CLOSURES"].get("decode") != 1:
        errors.append(f"LOOP_CLOSURES rejections {reasons['LOOP_CLOSURES']}")
    # What the daemon published (its own count: lcm-logger may lose a few of the outputs under load).  Dead reckoning
    # publishes a pose per accepted odometry message: the robot's 300 alone (before the guard: 11 of them).
    published = dict(zip(final.output_channels, final.output_counts)).get("FUSED_POSE", 0)
    if published < ODOMETRY - never_arrived:
        errors.append(f"{published} FUSED_POSE published for the robot's {ODOMETRY} odometry messages (and the names')")
    robot = [f for f in fused if f.source == "robot"]
    for e in errors:
        print("FAIL:", e)
    print(f"ODOMETRY received {odo.received} decoded {odo.decoded} lost {odo.lost} reasons {reasons['ODOMETRY']}; "
          f"LANDMARKS {reasons['LANDMARKS']}; BEARINGS decoded {br.decoded} {reasons['BEARINGS']}; "
          f"LOOP_CLOSURES {reasons['LOOP_CLOSURES']}; FUSED_POSE published {published}, of the robot on the bus {len(robot)}")
    return 1 if errors else 0


if __name__ == "__main__":
    if sys.argv[1] == "make":
        make(sys.argv[2])
    else:
        sys.exit(check(sys.argv[2]))
