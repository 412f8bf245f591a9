#!/usr/bin/env bash
# The Foxglove bridge of two builds under bench/foxglove.sh's load, runs interleaved (OLD, NEW, OLD, NEW, ...: the
# machine is shared, so both see the same load): each build's median CPU and latencies per case, every run's figure
# and the ratio of the medians (bench/foxglove_summary.py --before-after).
#   bench/foxglove_before_after.sh OLD_BUILD NEW_BUILD OUT [ROUNDS=3]     (CASES as for bench/foxglove.sh)
set -euo pipefail
if [ $# -lt 3 ]; then sed -n '2,5p' "$0" >&2; exit 2; fi
root=$(cd "$(dirname "$0")/.." && pwd)
old=$1 new=$2 out=$3 rounds=${4:-3}
mkdir -p "$out"
out=$(cd "$out" && pwd)
# One load for every run.
PYTHONPATH="$(cd "$new/lcmtypes/python" && pwd):$root/tests/e2e" python3 "$root/bench/foxglove_load.py" "$out/load.lcm"
olds=() news=()
for i in $(seq "$rounds"); do
  for build in old new; do
    dir="$out/$build.$i"
    mkdir -p "$dir"; ln -sf "$out/load.lcm" "$dir/load.lcm"
    if [ $build = old ]; then b=$old; olds+=("$dir"); else b=$new; news+=("$dir"); fi
    MINUTES=0 "$root/bench/foxglove.sh" "$b" "$dir" > "$dir.txt"
  done
done
python3 "$root/bench/foxglove_summary.py" --before-after "${olds[@]}" -- "${news[@]}" | tee "$out/before_after.md"
