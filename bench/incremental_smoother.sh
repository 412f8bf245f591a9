#!/bin/bash
# Incremental smoother against iSAM2 in the same run: `sextant optimize --incremental` (one pose per update) and
# GTSAM's iSAM2 driven the same way (isam2_bench, default ISAM2Params) on M3500, sphere2500, city10000 and torus3D,
# RUNS rounds (default 3; TORUS_RUNS for torus3D, default RUNS).  Within a round every data set runs sextant and the
# peer back to back, the order alternating between rounds, so that both see the same machine load.  One JSON per run
# in OUT, then bench/incremental_summary.py prints the medians and the ratios sextant / iSAM2 (mean, p99, max step;
# final chi2 against sextant's batch solve of the same graph from the same start).
#
# The peer is not part of the project: build it once per machine outside the repository,
#   ../shared/peers/gtsam/build.sh DIR          (about 15 minutes on two cores)
# and give its driver in ISAM2_BENCH=DIR/isam2_build/isam2_bench.  Without it the bench says so and measures sextant
# alone (REQUIRE_PEER=1: it stops instead).
# With a second build directory BASE, every sextant run of BUILD is followed by the same run of BASE, and the summary
# adds new / base ratios.  SKIPS: sextant's --relin-skip values (default 1, its default; iSAM2 runs with its own 10).
# DATASETS overrides the list of sets (names in ../shared/data/posegraph, without .g2o).
# Usage: [ISAM2_BENCH=PATH] bench/incremental_smoother.sh [BUILD_DIR] [OUT_DIR] [BASE_BUILD_DIR]
#   e.g. ISAM2_BENCH=/work/gtsam-peer/isam2_build/isam2_bench RUNS=3 bench/incremental_smoother.sh build /tmp/inc
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$here/build}
out=${2:-$(mktemp -d)}
base=${3:-}
data=$here/../shared/data/posegraph
runs=${RUNS:-3}
peer=${ISAM2_BENCH:-}
mkdir -p "$out"
if [ -z "$peer" ] || [ ! -x "$peer" ]; then
  echo "iSAM2 peer NOT BUILT (ISAM2_BENCH='$peer' is not an executable): measuring sextant alone, no ratios to" \
       "iSAM2.  Build it with ../shared/peers/gtsam/build.sh DIR, then ISAM2_BENCH=DIR/isam2_build/isam2_bench." >&2
  [ "${REQUIRE_PEER:-0}" = 1 ] && exit 2
  peer=""
  echo "no peer" > "$out/PEER_NOT_BUILT"
fi
load() { cut -d' ' -f1-3 /proc/loadavg; }
run_sextant() {  # label bin ds skip round
  "$2" optimize "$data/$3.g2o" --incremental --relin-skip "$4" --json > "$out/$3.s$4.$1.r$5.json"
  echo "$3 round $5 sextant $1 skip $4, load $(load)" >&2
}
run_peer() {  # ds round
  [ -n "$peer" ] || return 0
  "$peer" "$data/$1.g2o" > "$out/$1.isam2.r$2.json"
  echo "$1 round $2 iSAM2, load $(load)" >&2
}
for r in $(seq 1 "$runs"); do
  for ds in ${DATASETS:-M3500 sphere2500 city10000 torus3D}; do
    [ "$ds" = torus3D ] && [ "$r" -gt "${TORUS_RUNS:-$runs}" ] && continue
    [ $((r % 2)) = 0 ] && run_peer "$ds" "$r"
    for skip in ${SKIPS:-1}; do
      run_sextant new "$build/bin/sextant" "$ds" "$skip" "$r"
      [ -n "$base" ] && run_sextant base "$base/bin/sextant" "$ds" "$skip" "$r"
    done
    [ $((r % 2)) = 1 ] && run_peer "$ds" "$r"
  done
done
python3 "$here/bench/incremental_summary.py" "$out"
