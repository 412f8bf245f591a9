#!/usr/bin/env bash
# make bench: every benchmark, results printed (copy the tables into bench/RESULTS.md with the date).
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
echo "== EKF-SLAM update (Google Benchmark, median of 5 repetitions)"
"$build/bin/ekf_update_benchmark" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
echo "== MRCLAM Dataset 7: dead reckoning, EKF localization, EKF-SLAM, FastSLAM 2.0 (100 and 1000 particles)"
bench/mrclam_filters.sh "$build"
echo "== FastSLAM 2.0 speed, MRCLAM robot 1, 100 particles (median of 3 replays)"
bench/fastslam_speed.sh "$build"
echo "== pose graphs against Ceres 2.1"
cmake -S ../shared/peers/ceres_posegraph -B build-bench/ceres -DCMAKE_BUILD_TYPE=Release > /dev/null
make -s -C build-bench/ceres
python3 bench/posegraph_vs_ceres.py "$build" build-bench/ceres/ceres_posegraph --reps 3 --out bench/results/graph.md
echo "== small pose graphs as whole processes against Ceres 2.1"
python3 bench/posegraph_vs_ceres.py "$build" build-bench/ceres/ceres_posegraph --process --reps 11 --datasets intel,kitti_00,kitti_02
