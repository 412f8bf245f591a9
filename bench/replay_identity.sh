#!/bin/bash
# Deterministic replay, one build against another (e.g. a refactoring against main): each run below is replayed by
# both builds and their TUM trajectories must be byte-identical.  The runs: the demo's planar run (simulate planar
# --seed 1 --duration 50 with the demo's in-view false alarms), a longer planar run (seed 3, 300 s), a 3-D run
# (simulate spatial --seed 2 --duration 300), and MRCLAM Dataset 7 robots 1-5 with config/mrclam.yaml when the data
# set is present.  The simulated logs are written by the NEW build (the simulator is deterministic).
# Usage: bench/replay_identity.sh NEW_BUILD_DIR OLD_BUILD_DIR [OUT_DIR]      exit 0: all identical
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
new=$1/bin/sextant
old=$2/bin/sextant
out=${3:-$(mktemp -d)}
mkdir -p "$out"
status=0
compare() {  # name log config
  local name=$1 log=$2 config=$3
  "$new" replay "$log" --config "$config" --tum-out "$out/$name.new.tum" > /dev/null
  "$old" replay "$log" --config "$config" --tum-out "$out/$name.old.tum" > /dev/null
  if cmp -s "$out/$name.new.tum" "$out/$name.old.tum"; then
    echo "$name: identical ($(wc -l < "$out/$name.new.tum") poses, sha256 $(sha256sum "$out/$name.new.tum" | cut -c1-16))"
  else
    echo "$name: DIFFERENT ($out/$name.new.tum against $out/$name.old.tum)"
    status=1
  fi
}
"$new" simulate planar -o "$out/demo.lcm" --seed 1 --duration 50 --tum-out "$out/demo_gt.txt" \
  --clutter 1 --clutter-region -30 -20 4 30 20 16 > /dev/null
compare demo "$out/demo.lcm" "$here/config/default.yaml"
"$new" simulate planar -o "$out/planar300.lcm" --seed 3 --duration 300 --tum-out "$out/planar300_gt.txt" > /dev/null
compare planar300 "$out/planar300.lcm" "$here/config/default.yaml"
"$new" simulate spatial -o "$out/spatial300.lcm" --seed 2 --duration 300 --tum-out "$out/spatial300_gt.txt" > /dev/null
compare spatial300 "$out/spatial300.lcm" "$here/config/default.yaml"
mrclam=$here/../shared/data/landmarks/MRCLAM_Dataset7
if [ -d "$mrclam" ]; then
  for r in 1 2 3 4 5; do
    "$new" convert mrclam "$mrclam" --robot $r -o "$out/mrclam7_r$r.lcm" --gt-out "$out/mrclam7_r${r}_gt.txt" > /dev/null
    compare "mrclam7_r$r" "$out/mrclam7_r$r.lcm" "$here/config/mrclam.yaml"
  done
fi
exit $status
