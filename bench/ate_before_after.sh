#!/usr/bin/env bash
# ATE of one estimator before and after a change that is meant to move it: two builds (OLD, NEW) replay the same
# logs with the same configs (this checkout's) and `sextant eval` scores each TUM file against the ground truth.
# The runs are bench/refactor_identity.sh's: the demo's simulated planar run, the 3-D simulated run, MRCLAM
# Dataset 7's robots with config/mrclam.yaml.  Also the largest difference in position between the two TUM files.
#
# Usage: [ESTIMATOR=graph] [ROBOTS="1 2 3 4 5"] bench/ate_before_after.sh OLD_BUILD NEW_BUILD   (a markdown table)
set -euo pipefail
if [ $# -ne 2 ]; then sed -n '2,7p' "$0" >&2; exit 2; fi
root=$(cd "$(dirname "$0")/.." && pwd)
old=$(cd "$1" && pwd) new=$(cd "$2" && pwd)
estimator=${ESTIMATOR:-graph}
data="$root/../shared/data"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

ate() { "$new/bin/sextant" eval --gt "$1" --est "$2" --json | python3 -c 'import json,sys; print("%.4f" % (1000 * json.load(sys.stdin)["ate_rmse"]))'; }
# The largest distance between the positions of two TUM files at the same stamps (m).
max_shift() {
  python3 - "$1" "$2" <<'EOP'
import sys
def read(p):
    out = {}
    for line in open(p):
        v = line.split()
        if len(v) >= 4 and not line.startswith("#"):
            out[v[0]] = tuple(float(x) for x in v[1:4])
    return out
a, b = read(sys.argv[1]), read(sys.argv[2])
common = sorted(set(a) & set(b))
d = max((sum((x - y) ** 2 for x, y in zip(a[t], b[t])) ** 0.5 for t in common), default=float("nan"))
print("%.2e m over %d poses%s" % (d, len(common), "" if len(a) == len(b) == len(common) else " (pose counts differ: %d / %d)" % (len(a), len(b))))
EOP
}
row() {  # row NAME LOG CONFIG GT
  for tag in old new; do
    b=$old; [ $tag = new ] && b=$new
    "$b/bin/sextant" replay "$2" --config "$3" --estimator "$estimator" --tum-out "$work/$tag.tum" > /dev/null
  done
  printf '| %s | %s | %s | %s |\n' "$1" "$(ate "$4" "$work/old.tum")" "$(ate "$4" "$work/new.tum")" "$(max_shift "$work/old.tum" "$work/new.tum")"
}

echo "| run ($estimator) | ATE before [mm] | ATE after [mm] | largest position difference |"
echo "|---|---|---|---|"
. "$root/scripts/demo_world.sh"
demo_config "$root/config/default.yaml" "$work/demo.yaml"
"$new/bin/sextant" simulate planar -o "$work/demo.lcm" --seed 1 --duration 50 --tum-out "$work/demo_gt.txt" \
  --clutter "$false_alarms" --clutter-region "${region_min[@]}" "${region_max[@]}" > /dev/null
row "demo (planar, 50 s)" "$work/demo.lcm" "$work/demo.yaml" "$work/demo_gt.txt"
"$new/bin/sextant" simulate spatial -o "$work/spatial.lcm" --seed 1 --duration 60 --tum-out "$work/spatial_gt.txt" > /dev/null
row "3-D run (60 s)" "$work/spatial.lcm" "$root/config/default.yaml" "$work/spatial_gt.txt"
for r in ${ROBOTS-1 2 3 4 5}; do
  "$new/bin/sextant" convert mrclam "$data/landmarks/MRCLAM_Dataset7" --robot "$r" -o "$work/r.lcm" --gt-out "$work/gt.txt" > /dev/null
  row "MRCLAM 7 robot $r" "$work/r.lcm" "$root/config/mrclam.yaml" "$work/gt.txt"
done
