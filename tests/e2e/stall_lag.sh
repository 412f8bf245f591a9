#!/usr/bin/env bash
# Lag made visible: sextantd stopped (SIGSTOP) for STALL_S (3 s) while a robot's odometry goes on at 10 Hz, over a
# real LCM bus in a private network namespace.  After SIGCONT the daemon publishes the backlog that waited in its
# socket; each of those FUSED_POSE messages says how late it is (fused_pose_t.lag_us at least the time it waited,
# the first at least the stall), and the poses outside the stall say they are not (stall_lag.py checks); the daemon's
# log warns of the stall once (or twice), not before.
set -euo pipefail
source "$(dirname "$0")/netns.bash"
require_netns
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT
stall=${STALL_S:-3}
printf 'daemon:\n  status_period_s: 0.5\nengine:\n  primary_estimator: dead_reckoning\n  filter:\n    type: none\n  graph:\n    enabled: false\n  association:\n    enabled: false\n' > "$work/config.yaml"

cat > "$work/run.sh" <<EOS
set -euo pipefail
source "$here/netns.bash"
lcm-logger -f "$work/bus.lcm" > /dev/null 2>&1 &
logger=\$!
"$SEXTANT_BIN/sextantd" --config "$work/config.yaml" --log-level info > "$work/daemon.log" 2>&1 &
daemon=\$!
wait_running \$daemon "$work/daemon.log" || { kill -INT \$logger; exit 1; }
python3 "$here/stall_lag.py" make "$work/odometry.lcm" \$(date +%s%6N)
lcm-logplayer "$work/odometry.lcm" &
player=\$!
sleep 3
date +%s%6N > "$work/stop"; kill -STOP \$daemon
sleep $stall
date +%s%6N > "$work/cont"; kill -CONT \$daemon
wait \$player
sleep 0.5
kill -TERM \$daemon
wait \$daemon || { echo "sextantd exited with \$?"; cat "$work/daemon.log"; exit 1; }
sleep 0.2
kill -INT \$logger; wait \$logger || true
EOS
in_netns bash "$work/run.sh"
python3 "$here/stall_lag.py" check "$work/bus.lcm" "$(cat "$work/stop")" "$(cat "$work/cont")"
# The daemon's log says it fell behind: after the stall, once or twice (the backlog may span two status periods),
# never while it kept up.
warned=$(grep -c "later than usual" "$work/daemon.log" || true)
if [ "$warned" -lt 1 ] || [ "$warned" -gt 2 ]; then
  echo "stall_lag: expected 1 or 2 warnings of a stall in the daemon's log, found $warned"; cat "$work/daemon.log"; exit 1
fi
echo "stall_lag: ok"
