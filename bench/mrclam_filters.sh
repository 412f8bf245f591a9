#!/usr/bin/env bash
# ATE of dead reckoning, EKF localization (known map) and EKF-SLAM on MRCLAM Dataset 7, robots 1-5.
# Usage: bench/mrclam_filters.sh [BUILD_DIR]   (prints a markdown table)
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
data="$root/../shared/data/landmarks/MRCLAM_Dataset7"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
printf 'daemon:\n  queue_capacity: 4096\nengine:\n  filter:\n    slam: true\n    initial_sigma_xy: 0.02\n    initial_sigma_theta: 0.02\n' > "$work/slam.yaml"
ate() { "$root/$build/bin/sextant" eval --gt "$1" --est "$2" --json | python3 -c 'import json,sys; print("%.3f" % json.load(sys.stdin)["ate_rmse"])'; }
echo "| robot | dead reckoning ATE [m] | EKF localization, known map [m] | EKF-SLAM [m] | SLAM / dead reckoning |"
echo "|---|---|---|---|---|"
for r in 1 2 3 4 5; do
  "$root/$build/bin/sextant" convert mrclam "$data" --robot $r -o "$work/r.lcm" --gt-out "$work/gt.txt" > /dev/null
  "$root/$build/bin/sextant" replay "$work/r.lcm" --config "$root/config/mrclam.yaml" --estimator dead_reckoning --tum-out "$work/dr.txt" > /dev/null
  "$root/$build/bin/sextant" replay "$work/r.lcm" --config "$root/config/mrclam.yaml" --tum-out "$work/loc.txt" > /dev/null
  "$root/$build/bin/sextant" replay "$work/r.lcm" --config "$work/slam.yaml" --tum-out "$work/slam.txt" > /dev/null
  dr=$(ate "$work/gt.txt" "$work/dr.txt"); loc=$(ate "$work/gt.txt" "$work/loc.txt"); slam=$(ate "$work/gt.txt" "$work/slam.txt")
  echo "| $r | $dr | $loc | $slam | $(python3 -c "print('%.2f' % ($slam / $dr))") |"
done
