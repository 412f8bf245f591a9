#!/usr/bin/env bash
# Shows that a refactor changed no behaviour: two builds (OLD before the change, NEW after it) replay the same logs
# with the same configs and must write byte-identical TUM trajectories, and `sextant optimize --incremental` must end
# at the same final chi2.
#
# Usage: bench/refactor_identity.sh OLD_BUILD NEW_BUILD        (build folders holding bin/sextant)
#   e.g. cmake -S /path/to/old/checkout -B build-old -DCMAKE_BUILD_TYPE=Release && cmake --build build-old
#        bench/refactor_identity.sh build-old build
# Environment: ROBOTS (MRCLAM robots, default "1 2 3 4 5"), GRAPHS (pose graphs, default "M3500 sphere2500 city10000"),
#              KEEP=1 keeps the work folder (its path is printed).
#
# What is compared (inputs are made once, by OLD; the configs are this checkout's, so both builds read the same):
#   demo      `make demo`'s simulated planar run (seed 1, 50 s, false alarms over the targets' region) with the demo's
#             config (config/default.yaml told the region, scripts/demo_world.sh), replayed;
#   spatial   a 3-D simulated run (seed 1, 60 s) with config/default.yaml;
#   mrclam    MRCLAM Dataset 7, each robot of ROBOTS, converted from ../shared/data with config/mrclam.yaml, and the
#             same log with EKF-SLAM and with FastSLAM 2.0 (the configs of bench/mrclam_filters.sh);
#   for every replay the TUM file of each estimator (--estimator dead_reckoning | ekf | pf | graph) and, for the graph,
#   its final keyframes rebuilt from TRAJECTORY as the bus's subscribers do (tests/e2e/lcmlog.py);
#   the simulator's and the MRCLAM converter's logs themselves (both builds make them; bytes compared);
#   optimize  `sextant optimize DATA.g2o --incremental --json`: final_chi2 and initial_chi2, printed with %.17g.
# Prints one row per item (identical / DIFFERENT) and exits 1 if any item differs, 2 on a usage or run error.
set -euo pipefail
if [ $# -ne 2 ]; then sed -n '2,9p' "$0" >&2; exit 2; fi
root=$(cd "$(dirname "$0")/.." && pwd)
old=$(cd "$1" && pwd) new=$(cd "$2" && pwd)
for b in "$old" "$new"; do
  [ -x "$b/bin/sextant" ] || { echo "refactor_identity: $b/bin/sextant not found (build it first)" >&2; exit 2; }
done
data="$root/../shared/data"
work=$(mktemp -d)
if [ "${KEEP:-0}" = 1 ]; then echo "work folder: $work"; else trap 'rm -rf "$work"' EXIT; fi

differences=0
rows=()
row() {  # row ITEM RESULT DETAIL
  rows+=("$(printf '| %-58s | %-9s | %s |' "$1" "$2" "$3")")
  [ "$2" = identical ] || differences=$((differences + 1))
}
digest() { sha256sum "$1" | cut -c1-12; }
size() { case "$1" in *.tum) echo "$(wc -l < "$1") poses" ;; *) echo "$(stat -c %s "$1") bytes" ;; esac; }
compare_files() {  # compare_files ITEM OLD_FILE NEW_FILE
  if [ ! -s "$2" ] && [ ! -s "$3" ]; then row "$1" DIFFERENT "both empty or missing: nothing compared"
  elif cmp -s "$2" "$3"; then row "$1" identical "sha256 $(digest "$2"), $(size "$2")"
  else row "$1" DIFFERENT "old $(digest "$2") ($(size "$2")), new $(digest "$3") ($(size "$3")), first difference: $(cmp "$2" "$3" 2>&1 | head -1)"
  fi
}

# The final keyframes of the graph from an --out-log, as TUM lines (the subscriber's rebuild of TRAJECTORY).
keyframes_tum() {  # keyframes_tum BUILD OUT_LOG TUM
  python3 - "$2" "$3" "$1/lcmtypes/python" "$root/tests/e2e" <<'EOP'
import sys
sys.path.insert(0, sys.argv[3]); sys.path.insert(0, sys.argv[4])
from lcmlog import read_log, TrajectoryRebuild
from sextant import trajectory_t
rebuild = TrajectoryRebuild()
for _, c, b in read_log(sys.argv[1]):
    if c == "TRAJECTORY":
        rebuild.add(trajectory_t.decode(b))
with open(sys.argv[2], "w") as f:
    for sender, source in sorted(rebuild.bodies):
        for k in rebuild.keyframes(source, sender):
            p, q = k.position, k.orientation
            f.write(f"{k.utime * 1e-6:.6f} {p[0]!r} {p[1]!r} {p[2]!r} {q[1]!r} {q[2]!r} {q[3]!r} {q[0]!r}\n")
EOP
}

# replay_both NAME LOG CONFIG ESTIMATORS...: each build replays LOG once per estimator; TUM files compared.
replay_both() {
  local name=$1 log=$2 config=$3; shift 3
  local e b tag
  for e in "$@"; do
    for tag in old new; do
      b=$old; [ $tag = new ] && b=$new
      local extra=()
      [ "$e" = graph ] && extra=(--out-log "$work/$name.$e.$tag.lcm")
      if ! "$b/bin/sextant" replay "$log" --config "$config" --estimator "$e" --tum-out "$work/$name.$e.$tag.tum" \
           "${extra[@]}" > "$work/$name.$e.$tag.out" 2>&1; then
        echo "refactor_identity: $tag build failed to replay $name ($e):" >&2; cat "$work/$name.$e.$tag.out" >&2; exit 2
      fi
      if [ "$e" = graph ]; then
        keyframes_tum "$b" "$work/$name.$e.$tag.lcm" "$work/$name.keyframes.$tag.tum"
        rm -f "$work/$name.$e.$tag.lcm"
      fi
    done
    compare_files "$name: replay TUM, $e" "$work/$name.$e.old.tum" "$work/$name.$e.new.tum"
    [ "$e" = graph ] && compare_files "$name: graph's final keyframes (TRAJECTORY)" \
      "$work/$name.keyframes.old.tum" "$work/$name.keyframes.new.tum"
  done
  return 0
}

# 1. The demo run.
. "$root/scripts/demo_world.sh"
demo_config "$root/config/default.yaml" "$work/demo.yaml"
for tag in old new; do
  b=$old; [ $tag = new ] && b=$new
  "$b/bin/sextant" simulate planar -o "$work/demo.$tag.lcm" --seed 1 --duration 50 --tum-out "$work/demo_gt.$tag.txt" \
    --clutter "$false_alarms" --clutter-region "${region_min[@]}" "${region_max[@]}" > /dev/null
done
compare_files "demo: simulated log (sextant simulate planar)" "$work/demo.old.lcm" "$work/demo.new.lcm"
replay_both demo "$work/demo.old.lcm" "$work/demo.yaml" dead_reckoning ekf graph

# 2. A 3-D simulated run.
for tag in old new; do
  b=$old; [ $tag = new ] && b=$new
  "$b/bin/sextant" simulate spatial -o "$work/spatial.$tag.lcm" --seed 1 --duration 60 > /dev/null
done
compare_files "spatial: simulated log (sextant simulate spatial)" "$work/spatial.old.lcm" "$work/spatial.new.lcm"
replay_both spatial "$work/spatial.old.lcm" "$root/config/default.yaml" dead_reckoning ekf graph

# 3. MRCLAM Dataset 7 (configs for EKF-SLAM and FastSLAM 2.0 as in bench/mrclam_filters.sh).
printf 'daemon:\n  queue_capacity: 4096\nengine:\n  filter:\n    slam: true\n    initial_sigma_xy: 0.02\n    initial_sigma_theta: 0.02\n' > "$work/slam.yaml"
printf 'daemon:\n  queue_capacity: 4096\nengine:\n  filter:\n    type: pf\n    slam: true\n    initial_sigma_xy: 0.02\n    initial_sigma_theta: 0.02\n    pf:\n      particles: 100\n      seed: 1\n' > "$work/pf.yaml"
for r in ${ROBOTS-1 2 3 4 5}; do
  for tag in old new; do
    b=$old; [ $tag = new ] && b=$new
    "$b/bin/sextant" convert mrclam "$data/landmarks/MRCLAM_Dataset7" --robot "$r" -o "$work/r$r.$tag.lcm" > /dev/null
  done
  compare_files "mrclam robot $r: converted log (sextant convert mrclam)" "$work/r$r.old.lcm" "$work/r$r.new.lcm"
  replay_both "mrclam robot $r" "$work/r$r.old.lcm" "$root/config/mrclam.yaml" dead_reckoning ekf graph
  replay_both "mrclam robot $r, EKF-SLAM" "$work/r$r.old.lcm" "$work/slam.yaml" ekf
  replay_both "mrclam robot $r, FastSLAM 2.0" "$work/r$r.old.lcm" "$work/pf.yaml" pf
  rm -f "$work"/r$r.*.lcm
done

# 4. Incremental smoothing of the standard pose graphs.
chi2() { python3 -c 'import json,sys; j=json.load(sys.stdin); print("initial %.17g final %.17g" % (j["initial_chi2"], j["final_chi2"]))'; }
for g in ${GRAPHS-M3500 sphere2500 city10000}; do
  o=$("$old/bin/sextant" optimize "$data/posegraph/$g.g2o" --incremental --json | chi2)
  n=$("$new/bin/sextant" optimize "$data/posegraph/$g.g2o" --incremental --json | chi2)
  if [ "$o" = "$n" ]; then row "optimize --incremental: $g" identical "$n"
  else row "optimize --incremental: $g" DIFFERENT "old $o; new $n"
  fi
done

echo "old: $old ($("$old/bin/sextant" --version))"
echo "new: $new ($("$new/bin/sextant" --version))"
printf '| %-58s | %-9s | %s |\n' item result detail
printf '|%s|%s|%s|\n' "$(printf -- '-%.0s' {1..60})" "-----------" "--------"
printf '%s\n' "${rows[@]}"
echo "$((${#rows[@]} - differences)) of ${#rows[@]} items identical"
[ "$differences" = 0 ] || exit 1
