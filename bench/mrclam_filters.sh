#!/usr/bin/env bash
# ATE of dead reckoning, EKF localization (known map), EKF-SLAM and FastSLAM 2.0 (SLAM, PF_PARTICLES particles,
# default "100 1000"; median over the seeds PF_SEEDS, default "1 2 3", each seed's ATE in brackets) on MRCLAM
# Dataset 7, robots 1-5 (ROBOTS, default "1 2 3 4 5").
# Usage: [PF_PARTICLES="100"] [PF_SEEDS="1"] [ROBOTS="1"] bench/mrclam_filters.sh [BUILD_DIR]   (prints a markdown table)
# Then the graph back end (odometry + landmark sightings) in a second table; GRAPH=0 skips it.  CONFIG (default
# config/mrclam.yaml) is the config of the dead-reckoning, EKF-localization and graph runs (e.g. a copy with one
# setting changed, for a before/after).
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
config=${CONFIG:-$root/config/mrclam.yaml}
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
  "$root/$build/bin/sextant" replay "$work/r.lcm" --config "$config" --estimator dead_reckoning --tum-out "$work/dr.txt" > /dev/null
  "$root/$build/bin/sextant" replay "$work/r.lcm" --config "$config" --estimator ekf --tum-out "$work/loc.txt" > /dev/null
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

# The graph back end (odometry + landmark sightings, no loop closures; engine.graph of config/mrclam.yaml): ATE of its
# online fused pose (FUSED_POSE_GRAPH: the latest optimized keyframe composed with the odometry since it) and of the
# final optimized keyframes (the last TRAJECTORY), next to dead reckoning.  GRAPH=0 skips it.
if [ "${GRAPH:-1}" != 0 ]; then
  echo
  echo "| robot | dead reckoning ATE [m] | graph, online fused pose [m] | online / DR | graph, final keyframes [m] | keyframes / DR | keyframes | landmarks | sightings accepted / rejected |"
  echo "|---|---|---|---|---|---|---|---|---|"
  for r in $robots; do
    "$root/$build/bin/sextant" convert mrclam "$data" --robot $r -o "$work/r.lcm" --gt-out "$work/gt.txt" > /dev/null
    "$root/$build/bin/sextant" replay "$work/r.lcm" --config "$config" --estimator dead_reckoning --tum-out "$work/dr.txt" > /dev/null
    "$root/$build/bin/sextant" replay "$work/r.lcm" --config "$config" --estimator graph --tum-out "$work/graph.txt" \
      --out-log "$work/graph_out.lcm" --json > "$work/graph.json"
    counts=$(python3 - "$work/graph_out.lcm" "$work/kf.txt" "$work/graph.json" "$root/$build/lcmtypes/python" "$root/tests/e2e" <<'EOP'
import json, sys
sys.path.insert(0, sys.argv[4]); sys.path.insert(0, sys.argv[5])
from lcmlog import read_log, TrajectoryRebuild
from sextant import trajectory_t
rebuild, source = TrajectoryRebuild(), None
for _, c, b in read_log(sys.argv[1]):
    if c == "TRAJECTORY":
        m = trajectory_t.decode(b)
        rebuild.add(m)
        source = m.source
with open(sys.argv[2], "w") as f:
    for k in rebuild.keyframes(source):
        p, q = k.position, k.orientation
        f.write(f"{k.utime * 1e-6:.6f} {p[0]:.9f} {p[1]:.9f} {p[2]:.9f} {q[1]:.9f} {q[2]:.9f} {q[3]:.9f} {q[0]:.9f}\n")
c = next(s["counters"] for s in json.load(open(sys.argv[3]))["stages"] if s["name"] == "graph")
print(f"{c['keyframes']} | {c['landmarks']} | {c['sightings_accepted']} / {c['sightings_rejected']}")
EOP
)
    rm -f "$work/graph_out.lcm"
    dr=$(ate "$work/gt.txt" "$work/dr.txt"); g=$(ate "$work/gt.txt" "$work/graph.txt"); kf=$(ate "$work/gt.txt" "$work/kf.txt")
    echo "| $r | $dr | $g | $(python3 -c "print('%.2f' % ($g / $dr))") | $kf | $(python3 -c "print('%.2f' % ($kf / $dr))") | $counts |"
  done
fi
