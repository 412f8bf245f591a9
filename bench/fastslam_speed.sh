#!/usr/bin/env bash
# FastSLAM 2.0 speed on MRCLAM Dataset 7: replays of one robot's log (~900 s of data) with only the particle
# filter running (dead reckoning, association and, when the build has it, the graph back end off), so the time is
# the filter's plus log reading.  One warm-up replay, then REPS timed ones; prints each and the median real-time
# factor (data seconds / wall seconds, from `sextant replay --json`).
# Usage: [PARTICLES=100] [ROBOT=1] [REPS=3] bench/fastslam_speed.sh [BUILD_DIR]
set -euo pipefail
build=${1:-build}
particles=${PARTICLES:-100}
robot=${ROBOT:-1}
reps=${REPS:-3}
root=$(cd "$(dirname "$0")/.." && pwd)
sextant="$root/$build/bin/sextant"
data="$root/../shared/data/landmarks/MRCLAM_Dataset7"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
config() {  # $1: extra engine lines
  printf "daemon:\n  queue_capacity: 4096\nengine:\n  dead_reckoning:\n    enabled: false\n  association:\n    enabled: false\n%b  filter:\n    type: pf\n    slam: true\n    initial_sigma_xy: 0.02\n    initial_sigma_theta: 0.02\n    pf:\n      particles: %d\n      seed: 1\n" "$1" "$particles" > "$work/pf.yaml"
}
"$sextant" convert mrclam "$data" --robot "$robot" -o "$work/r.lcm" --gt-out "$work/gt.txt" > /dev/null
config '  graph:\n    enabled: false\n'
if ! "$sextant" replay "$work/r.lcm" --config "$work/pf.yaml" > /dev/null 2> "$work/err"; then
  grep -q "graph" "$work/err" || { cat "$work/err" >&2; exit 1; }
  config ''  # a build without the graph stage
  "$sextant" replay "$work/r.lcm" --config "$work/pf.yaml" > /dev/null
fi
factors=()
for i in $(seq "$reps"); do
  f=$("$sextant" replay "$work/r.lcm" --config "$work/pf.yaml" --json | python3 -c 'import json,sys; j=json.load(sys.stdin); print("%.1f %.2f" % (j["realtime_factor"], j["wall_seconds"]))')
  echo "replay $i: real-time factor ${f% *}x, ${f#* } s wall"
  factors+=("${f% *}")
done
printf '%s\n' "${factors[@]}" | sort -g | awk '{a[NR]=$1} END {print "median real-time factor: " a[int((NR+1)/2)] "x over " NR " replays"}'
