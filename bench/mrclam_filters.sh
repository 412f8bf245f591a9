#!/usr/bin/env bash
# ATE of dead reckoning, EKF localization (known map), EKF-SLAM and FastSLAM 2.0 (SLAM, PF_PARTICLES particles,
# default "100 1000"; median over the seeds PF_SEEDS, default "1 2 3", each seed's ATE in brackets) on MRCLAM
# Dataset 7, robots 1-5 (ROBOTS, default "1 2 3 4 5").
# Usage: [PF_PARTICLES="100"] [PF_SEEDS="1"] [ROBOTS="1"] bench/mrclam_filters.sh [BUILD_DIR]   (prints a markdown table)
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
data="$root/../shared/data/landmarks/MRCLAM_Dataset7"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
printf 'daemon:\n  queue_capacity: 4096\nengine:\n  filter:\n    slam: true\n    initial_sigma_xy: 0.02\n    initial_sigma_theta: 0.02\n' > "$work/slam.yaml"
particles=${PF_PARTICLES-100 1000}
seeds=${PF_SEEDS:-1 2 3}
robots=${ROBOTS:-1 2 3 4 5}
for n in $particles; do
  for seed in $seeds; do
    printf 'daemon:\n  queue_capacity: 4096\nengine:\n  filter:\n    type: pf\n    slam: true\n    initial_sigma_xy: 0.02\n    initial_sigma_theta: 0.02\n    pf:\n      particles: %d\n      seed: %d\n' "$n" "$seed" > "$work/pf$n-$seed.yaml"
  done
done
median() { python3 -c 'import statistics,sys; print("%.3f" % statistics.median(float(x) for x in sys.argv[1:]))' "$@"; }
ate() { "$root/$build/bin/sextant" eval --gt "$1" --est "$2" --json | python3 -c 'import json,sys; print("%.3f" % json.load(sys.stdin)["ate_rmse"])'; }
pf_head=""; pf_rule=""
for n in $particles; do pf_head="$pf_head FastSLAM 2.0, $n particles, median [m] (per seed) | FastSLAM $n / dead reckoning |"; pf_rule="$pf_rule---|---|"; done
echo "| robot | dead reckoning ATE [m] | EKF localization, known map [m] | EKF-SLAM [m] | SLAM / dead reckoning |$pf_head"
echo "|---|---|---|---|---|$pf_rule"
for r in $robots; do
  "$root/$build/bin/sextant" convert mrclam "$data" --robot $r -o "$work/r.lcm" --gt-out "$work/gt.txt" > /dev/null
  "$root/$build/bin/sextant" replay "$work/r.lcm" --config "$root/config/mrclam.yaml" --estimator dead_reckoning --tum-out "$work/dr.txt" > /dev/null
  "$root/$build/bin/sextant" replay "$work/r.lcm" --config "$root/config/mrclam.yaml" --estimator ekf --tum-out "$work/loc.txt" > /dev/null
  "$root/$build/bin/sextant" replay "$work/r.lcm" --config "$work/slam.yaml" --estimator ekf --tum-out "$work/slam.txt" > /dev/null
  dr=$(ate "$work/gt.txt" "$work/dr.txt"); loc=$(ate "$work/gt.txt" "$work/loc.txt"); slam=$(ate "$work/gt.txt" "$work/slam.txt")
  pf_cells=""
  for n in $particles; do
    per_seed=""
    for seed in $seeds; do
      "$root/$build/bin/sextant" replay "$work/r.lcm" --config "$work/pf$n-$seed.yaml" --estimator pf --tum-out "$work/pf.txt" > /dev/null
      per_seed="$per_seed $(ate "$work/gt.txt" "$work/pf.txt")"
    done
    pf=$(median $per_seed)
    pf_cells="$pf_cells $pf ($(echo $per_seed | tr ' ' '/')) | $(python3 -c "print('%.2f' % ($pf / $dr))") |"
  done
  echo "| $r | $dr | $loc | $slam | $(python3 -c "print('%.2f' % ($slam / $dr))") |$pf_cells"
done
