#!/usr/bin/env bash
# The fleet benchmark on UTIAS MRCLAM Dataset 7 (../shared/data/landmarks/MRCLAM_Dataset7, read in place), robots
# ROBOTS (default "1 2 3 4 5"), three estimates side by side:
#  (a) today's single-robot graphs: each robot converted alone (`--robot N`: its odometry starts on its true pose, so
#      every robot's map frame is the Vicon frame) and replayed with config/mrclam.yaml; the online fused pose's ATE
#      (`sextant eval`, per robot alignment), and the final keyframes of the five replays under one alignment
#      (`sextant eval fleet` over the five output logs: "fleet frame", which the true starts hand them for free);
#  (b) the fleet: all robots in one log (`--robots`: each odometry in its own frame, robot sightings kept), replayed
#      with config/mrclam_fleet.yaml; each robot's online fused-pose ATE (graph), its final keyframes' ATE under one
#      alignment for the whole fleet (keyframes and landmarks together) and under its own, the map frame it ended
#      in, and the landmarks' RMSE under the same alignment;
#  (c) EKF localization on the surveyed map (config/mrclam.yaml's filter) on each single-robot log.
# Usage: bench/fleet.sh BUILD_DIR OUT_DIR  ->  OUT_DIR/fleet.md (the table and the commands), OUT_DIR/*.json (the
# raw figures: `sextant eval fleet --json` and `sextant replay --json` of the fleet run).
set -euo pipefail
if [ $# -ne 2 ]; then
  echo "usage: $0 BUILD_DIR OUT_DIR" >&2
  exit 2
fi
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "$1" && pwd)
mkdir -p "$2"
out=$(cd "$2" && pwd)
sextant="$build/bin/sextant"
data="$root/../shared/data/landmarks/MRCLAM_Dataset7"
robots=${ROBOTS:-1 2 3 4 5}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

ate() { "$sextant" eval --gt "$1" --est "$2" --json | python3 -c 'import json,sys; print("%.3f" % json.load(sys.stdin)["ate_rmse"])'; }

list=$(echo $robots | tr ' ' ',')
"$sextant" convert mrclam "$data" --robots "$list" -o "$work/fleet.lcm" --gt-out "$work/fleet_gt_" > "$out/fleet_convert.txt"
# The landmarks' surveyed positions, for the single-robot maps too.
cp "$work/fleet_gt_landmarks.txt" "$work/single_gt_landmarks.txt"

# (a) and (c): one robot at a time.
single_logs=()
for r in $robots; do
  "$sextant" convert mrclam "$data" --robot "$r" -o "$work/r$r.lcm" --gt-out "$work/single_gt_robot$r.txt" > /dev/null
  "$sextant" replay "$work/r$r.lcm" --config "$root/config/mrclam.yaml" --estimator graph --tum-out "$work/graph$r.txt" \
    --out-log "$work/single_out$r.lcm" > /dev/null
  "$sextant" replay "$work/r$r.lcm" --config "$root/config/mrclam.yaml" --estimator ekf --tum-out "$work/ekf$r.txt" > /dev/null
  echo "$r $(ate "$work/single_gt_robot$r.txt" "$work/graph$r.txt") $(ate "$work/single_gt_robot$r.txt" "$work/ekf$r.txt")" >> "$work/single.txt"
  single_logs+=(--out-log "$work/single_out$r.lcm")
done
"$sextant" eval fleet "${single_logs[@]}" --gt-prefix "$work/single_gt_" --json > "$out/single_fleet_eval.json"

# (b) the fleet in one log and one replay.
start=$(date +%s.%N)
fleet_status=0
"$sextant" replay "$work/fleet.lcm" --config "$root/config/mrclam_fleet.yaml" --out-log "$work/fleet_out.lcm" --json \
  > "$out/fleet_replay.json" 2> "$out/fleet_replay.err" || fleet_status=$?
seconds=$(python3 -c "import time; print('%.1f' % (time.time() - $start))")
if [ "$fleet_status" = 0 ]; then
  "$sextant" eval fleet --out-log "$work/fleet_out.lcm" --gt-prefix "$work/fleet_gt_" --estimator graph --json \
    > "$out/fleet_eval.json"
else
  echo '{}' > "$out/fleet_eval.json"
fi

python3 - "$work/single.txt" "$out/single_fleet_eval.json" "$out/fleet_eval.json" "$out/fleet_replay.err" \
  "$seconds" "$list" > "$out/fleet.md" <<'EOP'
import json, sys
single = {f"robot{l.split()[0]}": l.split()[1:] for l in open(sys.argv[1])}
sf, fl = json.load(open(sys.argv[2])), json.load(open(sys.argv[3]))
err, seconds, robots = open(sys.argv[4]).read().strip(), sys.argv[5], sys.argv[6]
num = lambda x: "n/a" if x is None else "%.3f" % x
print(f"# Fleet benchmark: MRCLAM Dataset 7, robots {robots}\n")
print("| robot | (a) single-robot graph, online ATE [m] | (a) single-robot graphs, fleet-frame ATE [m] | "
      "(b) fleet graph, online ATE [m] | (b) / (a) online | (b) online, since joined [m] | since joined / (a) | (b) fleet-frame ATE [m] | "
      "(b) own-alignment ATE [m] | (b) map frame | (c) EKF localization, surveyed map [m] |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for body, (graph, ekf) in single.items():
    a = sf.get("robots", {}).get(body, {})
    b = fl.get("robots", {}).get(body, {})
    online = b.get("online_ate_rmse")
    ratio = "n/a" if online is None else "%.2f" % (online / float(graph))
    joined = b.get("online_joined_ate_rmse")
    joined_ratio = "n/a" if joined is None else "%.2f" % (joined / float(graph))
    print(f"| {body} | {graph} | {num(a.get('fleet_ate_rmse'))} | {num(online)} | {ratio} | "
          f"{num(joined)} | {joined_ratio} | "
          f"{num(b.get('fleet_ate_rmse'))} | {num(b.get('own_ate_rmse'))} | {b.get('frame', 'n/a') or '(own)'} | {ekf} |")
print()
print(f"Landmarks under the one alignment: (a) {sf.get('landmarks_matched', 0)} of map frame "
      f"'{sf.get('landmark_frame', '')}' matched (each single-robot replay has its own map), RMSE "
      f"{num(sf.get('landmark_rmse'))} m; (b) {fl.get('landmarks_matched', 0)} matched, RMSE {num(fl.get('landmark_rmse'))} m "
      f"(map frame '{fl.get('landmark_frame', '')}', {fl.get('frames', 0)} map frame(s) among the robots).")
print(f"\nFleet replay: {seconds} s wall" + (f"; it failed: {err}" if err and not fl else "") + ".")
print("""
Commands (bench/fleet.sh BUILD OUT): per robot N, `sextant convert mrclam DIR --robot N -o rN.lcm --gt-out gt_robotN.txt`,
`sextant replay rN.lcm --config config/mrclam.yaml --estimator graph|ekf --tum-out EST.txt [--out-log outN.lcm]`,
`sextant eval --gt gt_robotN.txt --est EST.txt`, and `sextant eval fleet --out-log out1.lcm ... --gt-prefix gt_` for the
single-robot graphs under one alignment; the fleet: `sextant convert mrclam DIR --robots 1-5 -o fleet.lcm --gt-out fleet_gt_`,
`sextant replay fleet.lcm --config config/mrclam_fleet.yaml --out-log fleet_out.lcm`,
`sextant eval fleet --out-log fleet_out.lcm --gt-prefix fleet_gt_ --estimator graph --json`.
ATE: RMSE of positions, associated by time within 0.02 s; online = FUSED_POSE as published, aligned per robot (SE(3)
Umeyama, `sextant eval`), all of them and those published in the map frame the robot ended in ("since joined");
fleet-frame = final keyframes (TRAJECTORY rebuilt) of all robots and the landmarks under one
SE(2) alignment; own-alignment = the same keyframes, SE(2) alignment per robot.""")
EOP
cat "$out/fleet.md"
