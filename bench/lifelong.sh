#!/usr/bin/env bash
# Lifelong real time: cost per update, memory and bus traffic against run length (bench/RESULTS.md,
# "Lifelong operation").
#   bench/lifelong.sh BUILD OUT [MINUTES ...]      (default minutes: 5 20 60)
# 1. Offline: simulated planar and spatial runs of each length (seeds 1 and 2) replayed with config/default.yaml
#    (lifelong on) and, for 5 and 60 minutes, with lifelong off (the full-history graph); per 5-minute segment: the
#    replay's real-time factor, the graph stage's time per event (p50/p99/max), the resident memory and the graph's
#    size; the ATE of the graph's fused pose (`sextant eval`).
# 2. Live: sextantd on a private bus fed the longest planar run at 10x by `sextant replay --realtime`, lcm-logger
#    recording the bus, sextantd's RSS sampled every 5 s: graph queue, drops, correction age, TRAJECTORY bytes per
#    second and largest message (bench/lifelong_summary.py reads everything).
# Runs take long (the 60-minute live run alone is 6 minutes): a benchmark, not a test.  LIVE=0 skips part 2;
# SEEDS="1" runs one seed, SCENARIOS="planar" one scenario, FULL_MINUTES="5" the full-history graph on 5-minute runs
# only (a 60-minute full-history replay takes about 10 minutes).
set -euo pipefail
build=${1:?usage: bench/lifelong.sh BUILD OUT [MINUTES ...]}
out=${2:?usage: bench/lifelong.sh BUILD OUT [MINUTES ...]}
shift 2
minutes=("$@")
[ ${#minutes[@]} -gt 0 ] || minutes=(5 20 60)
root=$(cd "$(dirname "$0")/.." && pwd)
bin=$(cd "$build/bin" && pwd)
mkdir -p "$out"
full="$out/full_history.yaml"
python3 - "$root/config/default.yaml" "$full" <<'EOP'
import sys
s = open(sys.argv[1]).read()
on = "    lifelong:\n      enabled: true\n"
if on not in s:
    sys.exit("lifelong.sh: config/default.yaml has no 'lifelong: enabled: true' block to turn off")
open(sys.argv[2], "w").write(s.replace(on, on.replace("true", "false")))
EOP

for scenario in ${SCENARIOS:-planar spatial}; do
  for m in "${minutes[@]}"; do
    for seed in ${SEEDS:-1 2}; do
      run="$out/${scenario}_${m}min_seed${seed}"
      [ -f "$run.lcm" ] || "$bin/sextant" simulate "$scenario" -o "$run.lcm" --seed "$seed" --duration $((m * 60)) \
          --tum-out "$run.gt.txt" > /dev/null
      modes=(lifelong)
      for f in ${FULL_MINUTES:-5 60}; do [ "$m" = "$f" ] && modes+=(full); done
      for mode in "${modes[@]}"; do
        cfg="$root/config/default.yaml"; [ "$mode" = full ] && cfg="$full"
        /usr/bin/time -f "%M" -o "$run.$mode.maxrss" "$bin/sextant" replay "$run.lcm" --config "$cfg" --estimator graph \
          --json --segment-seconds 300 --tum-out "$run.$mode.tum" > "$run.$mode.json"
        "$bin/sextant" eval --gt "$run.gt.txt" --est "$run.$mode.tum" --json > "$run.$mode.eval.json"
        rm -f "$run.$mode.tum"
        echo "$(basename "$run") $mode: done"
      done
    done
  done
done

if [ "${LIVE:-1}" = 1 ]; then
  m=${minutes[-1]}
  run="$out/planar_${m}min_seed1"
  source "$root/tests/e2e/netns.bash"
  cat > "$out/live.sh" <<EOS
set -euo pipefail
source "$root/tests/e2e/netns.bash"
lcm-logger -f "$out/live_bus.lcm" > /dev/null 2>&1 &
logger=\$!
"$bin/sextantd" --config "$root/config/default.yaml" --log-level warn > "$out/live_daemon.log" 2>&1 &
daemon=\$!
sleep 1
( while kill -0 \$daemon 2> /dev/null; do echo "\$(date +%s) \$(awk '/VmRSS/ {print \$2}' /proc/\$daemon/status)"; sleep 5; done ) \
  > "$out/live_rss.txt" &
sampler=\$!
"$bin/sextant" replay "$run.lcm" --realtime --speed 10 > /dev/null
sleep 3
kill -TERM \$daemon; wait \$daemon || true
kill -INT \$logger; wait \$logger || true
wait \$sampler || true
EOS
  in_netns bash "$out/live.sh"
fi
python3 "$root/bench/lifelong_summary.py" "$out" "$build/lcmtypes/python" "$root/tests/e2e" | tee "$out/summary.md"
