"""`sextant convert rosbag` on robot_localization's bag 1 (../shared/data/inertial) against python3-rosbag's own
reading of the same bag: every message of every topic arrives, on its channel, with its stamp and values (the pose
covariance rotated into the body frame); and `sextant convert euroc` against the CSV files read here."""
import csv
import os

import rosbag  # python3-rosbag, ROS's own Python reader: independent of the C++ library the converter uses
import sextant

from conftest import SHARED, tool

BAG = os.path.join(SHARED, "data", "inertial", "robot_localization_bag1", "test1.bag")
EUROC = os.path.join(SHARED, "data", "inertial", "euroc_v1_02_excerpt")


def stamp(header):
    return header.stamp.secs * 1000000 + header.stamp.nsecs // 1000


def rotation(w, x, y, z):
    n = (w * w + x * x + y * y + z * z) ** 0.5
    w, x, y, z = w / n, x / n, y / n, z / n
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def body_covariance(q, cov):
    """diag(R^T, R^T) cov diag(R, R): ROS's parent-frame pose covariance as sextant's body-frame one."""
    R = rotation(q.w, q.x, q.y, q.z)
    T = [[0.0] * 6 for _ in range(6)]
    for b in (0, 3):
        for i in range(3):
            for j in range(3):
                T[b + i][b + j] = R[j][i]
    C = [cov[6 * i:6 * i + 6] for i in range(6)]
    TC = [[sum(T[i][k] * C[k][j] for k in range(6)) for j in range(6)] for i in range(6)]
    return [sum(TC[i][k] * T[j][k] for k in range(6)) for i in range(6) for j in range(6)]


def close(a, b, tol=1e-12):
    return len(a) == len(b) and all(abs(x - y) <= tol * (1 + abs(y)) for x, y in zip(a, b))


def test_rosbag_bag1_against_python_rosbag(tmp_path):
    out = tmp_path / "bag1.lcm"
    printed = tool("convert", "rosbag", BAG, "-o", out, "--frame", "base_link=husky", "--frame", "imu_link=husky",
                   "--frame", "/gps=husky")
    assert "IMU 11865" in printed and "ODOMETRY 3952" in printed and "GNSS 989" in printed, printed

    ros = {}
    for topic, msg, _ in rosbag.Bag(BAG).read_messages():
        ros.setdefault(topic, []).append(msg)
    lcm = {}
    for ts, channel, data in sextant.read_log(str(out)):
        m = sextant.decode(data)
        assert ts == m["utime"]
        lcm.setdefault(channel, []).append(m)
    assert {c: len(v) for c, v in lcm.items()} == {"IMU": 11865, "ODOMETRY": 3952, "GNSS": 989}
    assert len(ros["/imu/data"]) == 11865 and len(ros["/husky_velocity_controller/odom"]) == 3952
    assert len(ros["/fix"]) == 989

    for m, r in zip(lcm["IMU"], ros["/imu/data"]):
        assert m["utime"] == stamp(r.header) and m["source"] == "husky" and m["frame"] == "imu_link"
        assert m["has_angular_velocity"] and m["has_linear_acceleration"] and m["has_orientation"]
        assert m["angular_velocity"] == [r.angular_velocity.x, r.angular_velocity.y, r.angular_velocity.z]
        assert m["linear_acceleration"] == [r.linear_acceleration.x, r.linear_acceleration.y, r.linear_acceleration.z]
        q = r.orientation  # normalized: the bag's are unit to about 1e-16
        assert close(m["orientation"], [v / (q.w ** 2 + q.x ** 2 + q.y ** 2 + q.z ** 2) ** 0.5 for v in (q.w, q.x, q.y, q.z)])
        assert m["orientation_covariance"] == list(r.orientation_covariance)
        assert m["angular_velocity_covariance"] == list(r.angular_velocity_covariance)
        assert m["linear_acceleration_covariance"] == list(r.linear_acceleration_covariance)

    for m, r in zip(lcm["ODOMETRY"], ros["/husky_velocity_controller/odom"]):
        p, q, t = r.pose.pose.position, r.pose.pose.orientation, r.twist.twist
        assert m["utime"] == stamp(r.header) and m["source"] == "husky" and not m["planar"]
        assert m["position"] == [p.x, p.y, p.z]
        assert close(m["orientation"], [v / (q.w ** 2 + q.x ** 2 + q.y ** 2 + q.z ** 2) ** 0.5 for v in (q.w, q.x, q.y, q.z)])
        assert close(m["covariance"], body_covariance(q, r.pose.covariance))
        assert m["has_twist"] and not m["has_increment_covariance"]
        assert m["linear_velocity"] == [t.linear.x, t.linear.y, t.linear.z]
        assert m["angular_velocity"] == [t.angular.x, t.angular.y, t.angular.z]
        assert m["twist_covariance"] == list(r.twist.covariance)

    for m, r in zip(lcm["GNSS"], ros["/fix"]):
        assert m["utime"] == stamp(r.header) and m["source"] == "husky" and m["frame"] == "/gps"
        assert m["status"] == r.status.status == 1 and m["covariance_type"] == r.position_covariance_type
        assert [m["latitude"], m["longitude"], m["altitude"]] == [r.latitude, r.longitude, r.altitude]
        assert m["position_covariance"] == list(r.position_covariance)

    for channel, msgs in lcm.items():
        assert [m["seq"] for m in msgs] == list(range(len(msgs))), channel


def test_rosbag_topic_mapping_and_errors(tmp_path):
    out = tmp_path / "imu_only.lcm"
    printed = tool("convert", "rosbag", BAG, "-o", out, "--topic", "/imu/data=IMU_HUSKY")
    assert "IMU_HUSKY 11865" in printed and "/fix 989" in printed, printed  # the unlisted topics are skipped
    channels = {c for _, c, _ in sextant.read_log(str(out))}
    assert channels == {"IMU_HUSKY"}
    sources = {sextant.decode(d)["source"] for _, _, d in sextant.read_log(str(out))}
    assert sources == {"imu_link"}  # an unmapped frame is its own body

    not_a_bag = tmp_path / "not.bag"
    not_a_bag.write_text("hello")
    import subprocess
    from conftest import BIN
    r = subprocess.run([os.path.join(BIN, "sextant"), "convert", "rosbag", str(not_a_bag), "-o", str(tmp_path / "x.lcm")],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "not.bag" in r.stderr, r.stderr
    r = subprocess.run([os.path.join(BIN, "sextant"), "convert", "rosbag", BAG, "-o", str(tmp_path / "x.lcm"),
                        "--frame", "imu_link"], capture_output=True, text=True)
    assert r.returncode == 2 and "--frame imu_link" in r.stderr, r.stderr


def test_euroc_against_the_csv(tmp_path):
    out, gt = tmp_path / "euroc.lcm", tmp_path / "gt.txt"
    printed = tool("convert", "euroc", EUROC, "-o", out, "--gt-out", gt)
    assert "7999 imu samples, 3340 truth" in printed, printed
    with open(os.path.join(EUROC, "imu0", "data.csv")) as f:
        rows = [[int(r[0])] + [float(x) for x in r[1:]] for r in csv.reader(f) if r and not r[0].startswith("#")]
    events = sextant.read_log(str(out))
    imu = [sextant.decode(d) for _, c, d in events if c == "IMU"]
    truth = [sextant.decode(d) for _, c, d in events if c == "GROUND_TRUTH"]
    assert len(imu) == len(rows) == 7999 and len(truth) == 3340
    assert [ts for ts, _, _ in events] == sorted(ts for ts, _, _ in events)
    for m, r in zip(imu, rows):
        assert m["utime"] == r[0] // 1000
        assert m["angular_velocity"] == r[1:4] and m["linear_acceleration"] == r[4:7]
        assert m["has_angular_velocity"] and m["has_linear_acceleration"] and not m["has_orientation"]
        # ADIS16448's white noise at 200 Hz: (1.6968e-4)^2 * 200 and (2e-3)^2 * 200
        assert abs(m["angular_velocity_covariance"][0] / 5.758e-6 - 1) < 1e-3
        assert abs(m["linear_acceleration_covariance"][8] / 8.0e-4 - 1) < 1e-3
    assert len([l for l in open(gt) if l.strip() and not l.startswith("#")]) == 3340
