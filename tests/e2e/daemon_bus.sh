#!/usr/bin/env bash
# sextantd over a real LCM bus in a private network namespace, fed and watched with LCM's own tools: a simulated run
# is played with lcm-logplayer, the bus is recorded with lcm-logger, and sextantd records what it receives.  Then a
# clean SIGTERM.  Checks: exit code 0, a complete recording, one FUSED_POSE per odometry message in order, values
# identical to a deterministic offline replay, status messages that account for everything, and TARGETS from the
# passive sensors' bearing scans (with false alarms among the targets' directions) at the simulated targets' true
# positions.
set -euo pipefail
source "$(dirname "$0")/netns.bash"
require_netns
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT

# False alarms in each passive sensor's field of view over the targets' region (1 per sensor and scan), and the
# association told that region and rate (per-sensor false-alarm densities, target prior).
"$SEXTANT_BIN/sextant" simulate planar -o "$work/sim.lcm" --seed 3 --duration 30 --clutter-region -30 -20 4 30 20 16 > /dev/null
printf 'daemon:\n  status_period_s: 0.5\nengine:\n  primary_estimator: dead_reckoning\n  association:\n    region_min: [-30, -20, 4]\n    region_max: [30, 20, 16]\n    false_alarms_per_scan: 1\n    target_prior: true\n    expected_targets: 4\n' > "$work/config.yaml"
"$SEXTANT_BIN/sextant" replay "$work/sim.lcm" --config "$work/config.yaml" --out-log "$work/replayed.lcm" > /dev/null

in_netns_fn feed_daemon "$work/daemon.log" "$work/bus.lcm" "$work/sim.lcm" 1.2 \
    --config "$work/config.yaml" --record "$work/record.lcm"
grep -q "recording closed" "$work/daemon.log" || { echo "no 'recording closed' in the daemon log"; cat "$work/daemon.log"; exit 1; }
python3 "$(dirname "$0")/check_daemon_run.py" "$work/sim.lcm" "$work/record.lcm" "$work/bus.lcm" "$work/replayed.lcm"
echo "daemon_bus: ok"
