#!/usr/bin/env bash
# The graph back end over a real LCM bus in a private network namespace, with the simulated front end closing the
# loop: a simulated planar run is played with lcm-logplayer into sextantd (default config: keyframes, proposals,
# incremental smoothing), `sextant matcher` answers its MATCH_REQUESTS from the run's ground truth (10 % unanswered,
# 10 % wrong), lcm-logger records the bus.  Checks: requests made and answered, every wrong answer either rejected or
# switched off (the final keyframes are far closer to the truth than dead reckoning), one FUSED_POSE "graph" per
# odometry message with strictly increasing times, TRAJECTORY published, and the status counters of the graph stage.
set -euo pipefail
source "$(dirname "$0")/netns.bash"
require_netns
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT

# No simulator loop closures: every loop comes from the matcher's answers to the daemon's own requests.
"$SEXTANT_BIN/sextant" simulate planar -o "$work/sim.lcm" --seed 5 --duration 60 --loop-distance 0 > /dev/null
printf 'daemon:\n  status_period_s: 0.5\nengine:\n  primary_estimator: graph\n  graph:\n    keyframes:\n      k1: 1.0\n' > "$work/config.yaml"

cat > "$work/run.sh" <<EOS
set -euo pipefail
source "$(dirname "$0")/netns.bash"
"$SEXTANT_BIN/sextant" matcher --truth "$work/sim.lcm" --failure-rate 0.1 --wrong-rate 0.1 --seed 3 --json \
    > "$work/matcher.json" 2> "$work/matcher.err" &
matcher=\$!
rc=0
feed_daemon "$work/daemon.log" "$work/bus.lcm" "$work/sim.lcm" 1.5 --config "$work/config.yaml" || rc=\$?
kill -TERM \$matcher; wait \$matcher || true
exit \$rc
EOS
in_netns bash "$work/run.sh"
python3 "$(dirname "$0")/check_graph_run.py" "$work/sim.lcm" "$work/bus.lcm" "$work/matcher.json"
echo "graph_bus: ok"
