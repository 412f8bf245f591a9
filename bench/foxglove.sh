#!/usr/bin/env bash
# The Foxglove bridge and MCAP files against the targets of bench/RESULTS.md ("See it in Foxglove").
#   bench/foxglove.sh BUILD OUT
# 1. Bridge: `sextant foxglove` on a private bus (network namespace) while `sextant replay --realtime` plays 10 bodies
#    x 100 Hz fused poses + each body's TRAJECTORY at 1 Hz + SEXTANT_STATUS at 1 Hz (foxglove_load.py, SECONDS long,
#    default 30) to 1 viewer, to 10 viewers, and to 1 viewer beside a stalled one (tests/viewer/bridge_client.mjs:
#    the reference ws-protocol client).  Per case: the latency the bridge adds to FUSED_POSE (viewer receive time -
#    bridge receive time, p50/p99 over every message of every viewer), the bridge's CPU (its user+system time over
#    the playing time, % of one core, from /proc), messages each viewer received and dropped, the stalled viewer's
#    queue.
# 2. MCAP: a 60-minute planar run (seed 1) replayed with config/default.yaml (lifelong); `convert mcap` of its output
#    log (what the daemon published) and of its input log: MB/s, sizes, then the reference reader
#    (tests/viewer/check_mcap.mjs) on both, compared with the logs.  MINUTES=N for a shorter run, MINUTES=0 for none.
# CASES="ten_viewers ..." runs only those bridge cases (before/after comparisons: interleave runs of two builds).
# Writes OUT/foxglove.md (the table) and the raw figures beside it.
set -euo pipefail
build=${1:?usage: bench/foxglove.sh BUILD OUT}
out=${2:?usage: bench/foxglove.sh BUILD OUT}
root=$(cd "$(dirname "$0")/.." && pwd)
bin=$(cd "$build/bin" && pwd)
lcmtypes=$(cd "$build/lcmtypes/python" && pwd)
mkdir -p "$out"
out=$(cd "$out" && pwd)
seconds=${SECONDS_OF_LOAD:-30}
minutes=${MINUTES:-60}
export PYTHONPATH="$lcmtypes:$root/tests/e2e"
source "$root/tests/e2e/netns.bash"
viewer="$root/tests/viewer"

# bridge_case NAME VIEWERS STALLED: one run inside a namespace; figures into $out/NAME.*
bridge_case() {
  local name=$1 viewers=$2 stalled=$3 dir="$out/$1"
  rm -rf "$dir"; mkdir -p "$dir"
  in_netns bash -c '
    set -euo pipefail
    bin=$1 viewer=$2 dir=$3 viewers=$4 stalled=$5 load=$6
    trap "kill \$(jobs -p) 2> /dev/null || true" EXIT
    "$bin/sextant" foxglove --port 8765 --stats-seconds 1 > "$dir/bridge.log" 2>&1 &
    bridge=$!
    for _ in $(seq 100); do grep -q "serving on" "$dir/bridge.log" && break; sleep 0.1; done
    clients=()
    for i in $(seq "$viewers"); do
      node "$viewer/bridge_client.mjs" ws://127.0.0.1:8765 "$dir/viewer$i.json" --bench --idle 3 > "$dir/viewer$i.log" 2>&1 &
      clients+=($!)
    done
    [ "$stalled" = 1 ] && { node "$viewer/bridge_client.mjs" ws://127.0.0.1:8765 "$dir/stalled.json" --stall > "$dir/stalled.log" 2>&1 & }
    for i in $(seq "$viewers"); do for _ in $(seq 100); do grep -q connected "$dir/viewer$i.log" && break; sleep 0.1; done; done
    sleep 0.5
    read -r _ _ _ _ _ _ _ _ _ _ _ _ _ ut0 st0 _ < /proc/$bridge/stat
    t0=$(date +%s.%N)
    "$bin/sextant" replay "$load" --realtime > /dev/null
    read -r _ _ _ _ _ _ _ _ _ _ _ _ _ ut1 st1 _ < /proc/$bridge/stat
    t1=$(date +%s.%N)
    echo "$(( ut1 + st1 - ut0 - st0 )) $(getconf CLK_TCK) $t0 $t1" > "$dir/cpu.txt"
    for c in "${clients[@]}"; do wait "$c" || true; done
    kill -INT $bridge; wait $bridge || true
  ' bench "$bin" "$viewer" "$dir" "$viewers" "$stalled" "$out/load.lcm"
}

require_netns
[ -f "$out/load.lcm" ] || python3 "$root/bench/foxglove_load.py" "$out/load.lcm" --seconds "$seconds"
declare -A case_args=([one_viewer]="1 0" [ten_viewers]="10 0" [stalled_viewer]="1 1")
for c in ${CASES:-one_viewer ten_viewers stalled_viewer}; do
  # shellcheck disable=SC2086  # "VIEWERS STALLED"
  bridge_case "$c" ${case_args[$c]:?unknown case $c}
done

if [ "$minutes" = 0 ]; then
  python3 "$root/bench/foxglove_summary.py" "$out" > "$out/foxglove.md"
  cat "$out/foxglove.md"; exit 0
fi

# MCAP of the 60-minute lifelong run.
run="$out/planar_${minutes}min"
[ -f "$run.lcm" ] || "$bin/sextant" simulate planar -o "$run.lcm" --seed 1 --duration $((minutes * 60)) > /dev/null
[ -f "$run.out.lcm" ] || "$bin/sextant" replay "$run.lcm" --config "$root/config/default.yaml" --out-log "$run.out.lcm" > /dev/null
for log in "$run.out" "$run"; do
  "$bin/sextant" convert mcap "$log.lcm" -o "$log.mcap" > "$log.convert.txt"
  python3 "$viewer/lcm_to_json.py" "$log.lcm" "$log.jsonl"
  node --max-old-space-size=8192 "$viewer/check_mcap.mjs" "$log.mcap" "$log.jsonl" > "$log.check.txt" 2>&1 \
    && echo ok >> "$log.check.txt" || echo FAILED >> "$log.check.txt"
  rm -f "$log.jsonl"
done

python3 "$root/bench/foxglove_summary.py" "$out" "$run" > "$out/foxglove.md"
cat "$out/foxglove.md"
