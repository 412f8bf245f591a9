"""The TUM loop-closure experiment (the Kinect visual-odometry paper's set-up), evaluation side: from an
lcm-logger recording of a sextantd run, writes the final
TRAJECTORY (optimized keyframes) and the dead-reckoning poses (raw odometry) at the keyframe times as TUM files."""
import sys

sys.path.insert(0, sys.argv[4])  # generated Python types
sys.path.insert(0, sys.argv[5])  # tests/e2e (lcmlog)
from lcmlog import read_log, TrajectoryRebuild  # noqa: E402
from sextant import fused_pose_t, trajectory_t  # noqa: E402


def tum_line(utime, p, q):
    return f"{utime * 1e-6:.6f} {p[0]:.9f} {p[1]:.9f} {p[2]:.9f} {q[1]:.9f} {q[2]:.9f} {q[3]:.9f} {q[0]:.9f}\n"


def main():
    bus, kf_out, odo_out = sys.argv[1:4]
    rebuild, source = TrajectoryRebuild(), None
    odometry = {}
    for _, c, b in read_log(bus):
        if c == "TRAJECTORY":
            m = trajectory_t.decode(b)
            rebuild.add(m)
            source = m.source
        elif c == "FUSED_POSE_DEAD_RECKONING":
            m = fused_pose_t.decode(b)
            odometry[m.utime] = m
    if source is None:
        sys.exit("no TRAJECTORY on the bus")
    with open(kf_out, "w") as kf, open(odo_out, "w") as od:
        for k in rebuild.keyframes(source):
            kf.write(tum_line(k.utime, k.position, k.orientation))
            if k.utime in odometry:
                o = odometry[k.utime]
                od.write(tum_line(o.utime, o.position, o.orientation))
    print(f"{len(rebuild.keyframes(source))} keyframes")


if __name__ == "__main__":
    main()
