#!/usr/bin/env bash
# A simulated fleet in lifelong mode against run length: `sextant simulate planar --robots N` for MINUTES, replayed
# with config/default.yaml (lifelong on) plus the fleet's markers, three times: with no wrong inter-robot loops
# ("0"), with 10 % wrong ones ("0.1"), and with the same realization as "0.1" but its wrong loops left out
# (`--omit-wrong-loops`, "0.1 omitted": every other message byte for byte the same).  Per 5-minute segment the
# real-time factor, the graph stage's p99/max time per event and the RSS; then every robot's fleet-frame ATE (`sextant
# eval fleet`), and whether the wrong loops fold the map: each robot's fleet-frame ATE with them against the run
# without them of the same realization ("0.1" / "0.1 omitted"; a run with no wrong loops at all draws different noise
# after the first wrong loop, so it measures the noise of one realization against another as well).
#   [SOLVE_PERIOD=S] bench/fleet_lifelong.sh BUILD OUT [MINUTES] [ROBOTS]   (defaults: 60 minutes, 8 robots, S = 0:
#   config/default.yaml's graph.solve_period_s, an update after every input; S = 0.05: at most one per 50 ms)
# -> OUT/fleet_lifelong.md (the table), OUT/*.json (replay --json), OUT/eval_*.txt.  A benchmark, not a test: the
# 60-minute run of 8 robots takes tens of minutes.
set -euo pipefail
build=${1:?usage: bench/fleet_lifelong.sh BUILD OUT [MINUTES] [ROBOTS]}
out=${2:?usage: bench/fleet_lifelong.sh BUILD OUT [MINUTES] [ROBOTS]}
minutes=${3:-60}
robots=${4:-8}
root=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out"
out=$(cd "$out" && pwd)
sextant="$(cd "$build/bin" && pwd)/sextant"
for variant in 0 0.1 0.1_omitted; do
  run="$out/fleet${robots}_${minutes}min_wrong${variant}"
  omit=()
  [ "$variant" = 0.1_omitted ] && omit=(--omit-wrong-loops)
  "$sextant" simulate planar --robots "$robots" --duration $((minutes * 60)) --seed 1 --wrong-loops "${variant%_*}" \
    "${omit[@]}" -o "$run.lcm" --config-out "$run.markers.yaml" > /dev/null
  markers=$(grep markers "$run.markers.yaml" | sed 's/^ *//')
  sed -e "s/^      markers: {}  .*/      $markers/" \
    -e "s/^    solve_period_s: 0 .*/    solve_period_s: ${SOLVE_PERIOD:-0}/" "$root/config/default.yaml" > "$run.yaml"
  grep -q "^    solve_period_s: ${SOLVE_PERIOD:-0}\$" "$run.yaml"  # the default config's line is still there
  /usr/bin/time -f "%M" -o "$run.maxrss" "$sextant" replay "$run.lcm" --config "$run.yaml" --estimator graph --json \
    --segment-seconds 300 --out-log "$run.out.lcm" > "$run.json"
  "$sextant" eval fleet --out-log "$run.out.lcm" --gt-prefix "${run}_gt_" --estimator graph > "$run.eval.txt"
  rm -f "$run.lcm" "$run.out.lcm"
done
python3 - "$out" "$robots" "$minutes" > "$out/fleet_lifelong.md" <<'EOP'
import json, os, sys
out, robots, minutes = sys.argv[1:4]
variants = ("0", "0.1", "0.1_omitted")
print(f"# Fleet in lifelong mode: {robots} simulated planar robots, {minutes} minutes, "
      f"graph.solve_period_s {os.environ.get('SOLVE_PERIOD', '0')}\n")
print("| wrong loops | real-time factor | segment | segment real-time factor | graph p99 (ms) | graph max (ms) | RSS (MB) |")
print("|---|---|---|---|---|---|---|")
for v in variants:
    run = f"{out}/fleet{robots}_{minutes}min_wrong{v}"
    d = json.load(open(run + ".json"))
    for s in d["segments"]:
        g = s["stages"]["graph"]
        print(f"| {v.replace('_', ' ')} | {d['realtime_factor']:.2f} | {s['start_s'] // 60}-{(s['start_s'] + s['data_s']) // 60} min | "
              f"{s['realtime_factor']:.2f} | {g['p99_ms']:.1f} | {g['max_ms']:.0f} | {s['rss_kb'] // 1024} |")
ate = {}
for v in variants:
    run = f"{out}/fleet{robots}_{minutes}min_wrong{v}"
    text = open(run + ".eval.txt").read().rstrip()
    ate[v] = {line.split()[0]: float(line.split()[4]) for line in text.splitlines() if line.startswith("robot")}
    print(f"\nFleet-frame ATE, wrong loops {v.replace('_', ' ')} (`sextant eval fleet`):\n\n```\n{text}\n```")
print("\nWrong loops against the same run without them (fleet-frame ATE, m; target: within 10 %):\n")
print("| robot | 0.1 omitted | 0.1 | ratio | 0 (other noise) |")
print("|---|---|---|---|---|")
for robot in sorted(ate["0.1"], key=lambda r: int(r[5:])):
    a, b = ate["0.1_omitted"][robot], ate["0.1"][robot]
    print(f"| {robot} | {a:.4f} | {b:.4f} | {b / a:.2f} | {ate['0'][robot]:.4f} |")
EOP
cat "$out/fleet_lifelong.md"
