#!/usr/bin/env bash
# sextant's MCAP files checked with the reference reader (@mcap/core, check_mcap.mjs) against the LCM logs they come
# from, decoded by LCM's own Python decoders: a simulated run's inputs (`convert mcap`), the replay's outputs
# (`convert mcap` of `replay --out-log`), and `replay --mcap-out` (inputs and outputs in one file), for one robot and
# for a fleet of three (each robot in its own map frame until it joins the first one's: every frame the poses and
# scenes are drawn in reaches "map" through /tf, the landmark maps and the frame list are there).  Then `convert lcm`
# of each converted file gives back the LCM log byte for byte.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
source "$here/node_env.bash"
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT
sextant="$SEXTANT_BIN/sextant"

"$sextant" simulate planar -o "$work/sim.lcm" --seed 5 --duration 30 > /dev/null
"$sextant" replay "$work/sim.lcm" --out-log "$work/out.lcm" --mcap-out "$work/replay.mcap" > /dev/null
for log in sim out; do
  "$sextant" convert mcap "$work/$log.lcm" -o "$work/$log.mcap" --chunk-size 65536
  python3 "$here/lcm_to_json.py" "$work/$log.lcm" "$work/$log.jsonl"
  node "$here/check_mcap.mjs" "$work/$log.mcap" "$work/$log.jsonl"
  "$sextant" convert lcm "$work/$log.mcap" -o "$work/$log.back.lcm"
  cmp "$work/$log.lcm" "$work/$log.back.lcm" || { echo "convert lcm of $log.mcap differs from $log.lcm"; exit 1; }
done
# The simulator stamps each event with its message's utime, so the replay's file (log_time = utime) compares with
# both logs together.
cat "$work/sim.jsonl" "$work/out.jsonl" > "$work/replay.jsonl"
node "$here/check_mcap.mjs" "$work/replay.mcap" "$work/replay.jsonl"

"$sextant" simulate planar --robots 3 -o "$work/fleet.lcm" --seed 5 --duration 90 --config-out "$work/fleet.yaml" > /dev/null
"$sextant" replay "$work/fleet.lcm" --config "$work/fleet.yaml" --out-log "$work/fleet_out.lcm" \
  --mcap-out "$work/fleet.mcap" > /dev/null
python3 "$here/lcm_to_json.py" "$work/fleet.lcm" "$work/fleet_in.jsonl"
python3 "$here/lcm_to_json.py" "$work/fleet_out.lcm" "$work/fleet_out.jsonl"
cat "$work/fleet_in.jsonl" "$work/fleet_out.jsonl" > "$work/fleet.jsonl"
node "$here/check_mcap.mjs" "$work/fleet.mcap" "$work/fleet.jsonl" \
  --require-topics LANDMARK_MAP,/sextant/landmark_map,/sextant/frames,/sextant/robot2/graph/pose
echo "mcap_reference: ok"
