#!/usr/bin/env bash
# Time per scan of the passive association at two commits on the same scans (bench/RESULTS.md,
# "Time per scan").  Usage: bench/assoc/compare_timing.sh OLD_COMMIT NEW_COMMIT [ROUNDS]
# Each commit's assoc/*.cpp and replay/assoc_experiment.cpp are compiled with the project's Release flags into
# bench/assoc/timing_driver.cpp (run_assoc_experiment with assoc-sim's options: spacing 1, P_D 0.9, classic cost,
# LR at its default gap); the two binaries then run alternately per seed.  Output lines: case seed old|new median_cpu_ms
# build_median_ms correct_rate gap_mean gap_max tuples_mean.
set -euo pipefail
old=$1 new=$2 rounds=${3:-1}
repo=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for v in old new; do
  commit=${!v}
  mkdir -p "$work/$v"
  git -C "$repo" archive "$commit" assoc replay daemon/runtime | tar -x -C "$work/$v"  # assoc_experiment and its headers
  g++ -O2 -DNDEBUG -std=c++20 -I"$work/$v" -isystem /usr/include/eigen3 "$work/$v"/assoc/*.cpp \
    "$work/$v/replay/assoc_experiment.cpp" "$repo/bench/assoc/timing_driver.cpp" -o "$work/$v/driver"
done
case_run() {
  local label=$1; shift
  for seed in 1 2 3; do
    for v in old new; do echo "$label $seed $v $("$work/$v/driver" "$@" --seed $seed)"; done
  done
}
for ((r = 1; r <= rounds; ++r)); do
  echo "# round $r start $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
  case_run grid3x20 --sensors 3 --targets 20 --clutter 5 --runs 20
  case_run grid3x20_prior --sensors 3 --targets 20 --clutter 5 --runs 20 --target-prior
  case_run uniform3x20 --sensors 3 --targets 20 --clutter 5 --runs 20 --uniform
  case_run uniform3x20_prior --sensors 3 --targets 20 --clutter 5 --runs 20 --uniform --target-prior
  case_run uniform5x50 --sensors 5 --targets 50 --clutter 10 --runs 5 --uniform
  case_run uniform5x50_prior --sensors 5 --targets 50 --clutter 10 --runs 5 --uniform --target-prior
  case_run uniform7x100_prior --sensors 7 --targets 100 --clutter 10 --runs 2 --uniform --target-prior
  case_run uniform7x100 --sensors 7 --targets 100 --clutter 10 --runs 2 --uniform
  echo "# round $r end $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)"
done
