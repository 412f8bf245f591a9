#!/usr/bin/env bash
# The duality gap over long runs of the 3-sensor timing scenarios (target: gap <= 1 % on every scan), at two commits
# on the same scans (bench/history/2026-11-22_to_2026-11-25.md, "Passive association").
# Usage: bench/assoc/long_gap.sh OLD NEW [SEEDS]
# Builds timing_driver.cpp against each commit's assoc/ as compare_timing.sh does, then runs 200 scans per seed
# (3 x 20 + 5 false alarms, grid and uniform, with and without the target prior), old and new alternately.
# Output lines: case seed old|new median_cpu_ms build_median_ms correct_rate gap_mean gap_max tuples_mean.
set -euo pipefail
old=$1 new=$2 seeds=${3:-5}
repo=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for v in old new; do
  commit=${!v}
  mkdir -p "$work/$v"
  git -C "$repo" archive "$commit" assoc replay/assoc_experiment.cpp replay/assoc_experiment.hpp | tar -x -C "$work/$v"
  g++ -O2 -DNDEBUG -std=c++20 -I"$work/$v" -isystem /usr/include/eigen3 "$work/$v"/assoc/*.cpp \
    "$work/$v/replay/assoc_experiment.cpp" "$repo/bench/assoc/timing_driver.cpp" -o "$work/$v/driver"
done
echo "# start $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
for label in grid3x20 grid3x20_prior uniform3x20 uniform3x20_prior; do
  args=(--sensors 3 --targets 20 --clutter 5 --runs 200)
  [[ $label == uniform* ]] && args+=(--uniform)
  [[ $label == *_prior ]] && args+=(--target-prior)
  for ((seed = 1; seed <= seeds; ++seed)); do
    for v in old new; do echo "$label $seed $v $("$work/$v/driver" "${args[@]}" --seed $seed)"; done
  done
done
echo "# end $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
