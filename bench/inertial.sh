#!/usr/bin/env bash
# The inertial benchmarks of bench/RESULTS.md, "Real robot sensors":
#  1. simulated spatial runs (IMU 200 Hz, wheel odometry 50 Hz, GNSS 5 Hz with 60 s outages every 180 s and 5 %
#     multipath, 20 min, seeds 1-5): odometry alone, the inertial filter and the inertial keyframe smoother against
#     the truth (bench/inertial_comparison.cpp);
#  2. robot_localization's bag 1 with its GNSS fused (bench/inertial/bag1_gnss.yaml): the filter's and the smoother's
#     horizontal RMS against the fixes, and with the fixes of 60 s in the middle removed, the distance to the first fix
#     after the gap (bench/inertial/bag1_gnss_eval.py).
# Usage: bench/inertial.sh BUILD OUT [PART]   (BUILD configured with -DSEXTANT_BENCH=ON; data from $SEXTANT_SHARED_DIR
# or /work/shared; PART 1 or 2 runs that part only).  Writes OUT/simulated.md and OUT/bag1_gnss.txt.
set -euo pipefail
build=${1:?usage: bench/inertial.sh BUILD OUT}
out=${2:?usage: bench/inertial.sh BUILD OUT}
src=$(cd "$(dirname "$0")/.." && pwd)
shared=${SEXTANT_SHARED_DIR:-/work/shared}
part=${3:-all}
mkdir -p "$out"

if [ "$part" != 2 ]; then "$build/bin/inertial_comparison" 5 1200 1 | tee "$out/simulated.md"; fi
[ "$part" != 1 ] || exit 0

bag="$shared/data/inertial/robot_localization_bag1/test1.bag"
[ -f "$bag" ] || { echo "SKIP bag 1: $bag not found"; exit 0; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$build/bin/sextant" convert rosbag "$bag" --frame base_link=husky --frame imu_link=husky --frame /gps=husky \
  -o "$work/bag1.lcm" > /dev/null
export PYTHONPATH="$build/lcmtypes/python:$src/tests/e2e${PYTHONPATH:+:$PYTHONPATH}"
# The gap: no fix in [170, 230) s after the first one (the run is 395 s).
python3 - "$work/bag1.lcm" "$work/gap.lcm" <<'EOP'
import sys
import lcmlog
from sextant import gnss_t
events = list(lcmlog.read_log(sys.argv[1]))
t0 = min(gnss_t.decode(b).utime for _, c, b in events if c == "GNSS") * 1e-6
with open(sys.argv[2], "wb") as f:
    n = 0
    for ts, c, b in events:
        if c == "GNSS" and 170 <= gnss_t.decode(b).utime * 1e-6 - t0 < 230:
            continue
        lcmlog.write_event(f, n, ts, c, b)
        n += 1
EOP
config="$src/bench/inertial/bag1_gnss.yaml"
for log in bag1 gap; do
  for e in inertial inertial_graph; do
    "$build/bin/sextant" replay "$work/$log.lcm" --config "$config" --estimator "$e" --tum-out "$work/$log.$e.txt" \
      > /dev/null
  done
done
{
  echo "all fixes:"
  python3 "$src/bench/inertial/bag1_gnss_eval.py" "$work/bag1.lcm" 170 230 \
    filter="$work/bag1.inertial.txt" smoother="$work/bag1.inertial_graph.txt"
  echo "no fix in [170, 230) s:"
  python3 "$src/bench/inertial/bag1_gnss_eval.py" "$work/bag1.lcm" 170 230 \
    filter="$work/gap.inertial.txt" smoother="$work/gap.inertial_graph.txt"
} | tee "$out/bag1_gnss.txt"
