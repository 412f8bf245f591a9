#!/usr/bin/env bash
# robot_localization's EKF test on its bag 1, through sextant as a user runs it: `sextant convert rosbag` turns the
# bag into an LCM log, sextantd with config/robot_localization_bag1.yaml takes it over a real LCM bus (a private
# network namespace, lcm-logplayer at 20x), and the last FUSED_POSE (the inertial filter) must lie within 1.0452 m of
# that test's final position (-40.0454, -76.9988, -2.6974) m in the odometry frame; `sextant replay --tum-out` of the
# same log must too.  The distances are printed.
set -euo pipefail
source "$(dirname "$0")/netns.bash"
require_netns
bag="$SEXTANT_SHARED_DIR/data/inertial/robot_localization_bag1/test1.bag"
[ -f "$bag" ] || { echo "SKIP: $bag not found"; exit 77; }
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT
config="$SEXTANT_SOURCE_DIR/config/robot_localization_bag1.yaml"

"$SEXTANT_BIN/sextant" convert rosbag "$bag" --frame base_link=husky --frame imu_link=husky -o "$work/bag1.lcm"
"$SEXTANT_BIN/sextant" replay "$work/bag1.lcm" --config "$config" --tum-out "$work/replay.txt" > /dev/null

cat > "$work/run.sh" <<EOS
set -euo pipefail
source "$(dirname "$0")/netns.bash"
lcm-logger -f "$work/bus.lcm" > /dev/null 2>&1 &
logger=\$!
"$SEXTANT_BIN/sextantd" --config "$config" > "$work/daemon.log" 2>&1 &
daemon=\$!
wait_running \$daemon "$work/daemon.log"
sleep 0.2
lcm-logplayer -s 20 "$work/bag1.lcm" > /dev/null
sleep 1
kill -TERM \$daemon
rc=0; wait \$daemon || rc=\$?
sleep 0.2
kill -INT \$logger; wait \$logger || true
[ \$rc -eq 0 ] || { echo "sextantd exited with \$rc"; cat "$work/daemon.log"; exit 1; }
EOS
in_netns bash "$work/run.sh"

python3 - "$work/bus.lcm" "$work/replay.txt" <<'EOP'
import math, sys
import lcmlog
from sextant import fused_pose_t
ref = (-40.0454, -76.9988, -2.6974)
tolerance = 1.0452
poses = [m for m in lcmlog.decode_all(sys.argv[1], "FUSED_POSE", fused_pose_t) if m.source == "husky"]
assert poses, "no FUSED_POSE of husky on the bus"
assert all(m.estimator == "inertial" for m in poses), "FUSED_POSE is not the inertial filter's"
live = poses[-1].position
with open(sys.argv[2]) as f:
    last = [l for l in f if l.strip() and not l.startswith("#")][-1].split()
replay = [float(v) for v in last[1:4]]
failed = False
for name, p in (("daemon over the bus", live), ("replay", replay)):
    d = math.dist(p, ref)
    print(f"{name}: final position ({p[0]:.4f}, {p[1]:.4f}, {p[2]:.4f}) m, {d:.4f} m from robot_localization's "
          f"(tolerance {tolerance} m), {len(poses)} fused poses on the bus")
    failed |= not d <= tolerance
sys.exit(1 if failed else 0)
EOP
