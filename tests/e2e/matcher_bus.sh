#!/usr/bin/env bash
# sextant matcher over a real LCM bus in a private network namespace: match requests between ground-truth stamps of
# a simulated run (plus some outside the truth, of an unknown body, and undecodable bytes) are played with
# lcm-logplayer; the answers are recorded with lcm-logger.  Checks: ids and times copied, correct answers within
# noise of the truth, wrong ones far from it, counts (--json on SIGTERM) that agree with the bus, and the same
# answers from a second run with the same seed.
set -euo pipefail
source "$(dirname "$0")/netns.bash"
require_netns
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT

"$SEXTANT_BIN/sextant" simulate planar -o "$work/sim.lcm" --seed 4 --duration 40 --landmarks 0 --targets 0 > /dev/null
python3 "$(dirname "$0")/matcher_requests.py" make "$work/sim.lcm" "$work/requests.lcm" "$work/expected.json"

cat > "$work/run.sh" <<EOS
set -euo pipefail
run() {  # run BUS.lcm COUNTS.json
  "$SEXTANT_BIN/sextant" matcher --truth "$work/sim.lcm" --sigma-t 0.05 --sigma-r 0.01 --failure-rate 0.1 \
      --wrong-rate 0.1 --seed 2 --delay-ms 20 --json > "\$2" 2> "$work/matcher.err" &
  matcher=\$!
  lcm-logger -f "\$1" > /dev/null 2>&1 &
  logger=\$!
  sleep 0.7
  lcm-logplayer "$work/requests.lcm" > /dev/null
  sleep 0.5
  kill -TERM \$matcher
  rc=0; wait \$matcher || rc=\$?
  sleep 0.2
  kill -INT \$logger; wait \$logger || true
  if [ \$rc -ne 0 ]; then echo "sextant matcher exited with \$rc"; cat "$work/matcher.err"; exit 1; fi
}
run "$work/bus1.lcm" "$work/counts1.json"
run "$work/bus2.lcm" "$work/counts2.json"
EOS
in_netns bash "$work/run.sh"
cmp "$work/counts1.json" "$work/counts2.json"
python3 "$(dirname "$0")/matcher_requests.py" check "$work/sim.lcm" "$work/expected.json" "$work/bus1.lcm" \
    "$work/counts1.json" "$work/bus2.lcm"
echo "matcher_bus: ok"
