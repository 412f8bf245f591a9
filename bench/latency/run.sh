#!/usr/bin/env bash
# sextantd's latency from an odometry message in to its FUSED_POSE out, over a real LCM bus (private network
# namespace), at 1 kHz while the graph back end works through city10000 in the background, next to the raw LCM
# round trip to a trivial echo measured in the same run.  city10000 is converted with `sextant convert g2o`
# (its chain as the odometry of body 'robot1', its other edges as LOOP_CLOSURES) and fed by daemon_latency under flow
# control; the daemon runs bench/latency/daemon.yaml (every city10000 pose a keyframe).
#
# Usage: bench/latency/run.sh BUILD [JSON_OUT]
#   BUILD     a build folder (relative to the project or absolute) with sextantd, sextant and daemon_latency:
#               cmake -S . -B build-lat -DCMAKE_BUILD_TYPE=Release -DSEXTANT_BENCH=ON
#               cmake --build build-lat -j2 --target sextantd sextant daemon_latency
#   JSON_OUT  optional: the figures as JSON (latency per channel; optimizer, drop and coalescing counters)
# Needs root (or user namespaces) for `unshare --net`; takes DURATION + about 10 s.
# env: DURATION (60 s), RATE (1000 Hz), WINDOW (4 poses ahead of the optimizer), FEED_RATE (1000 poses/s),
#      GRAPH (city10000.g2o in ../shared/data/posegraph), CONFIG (bench/latency/daemon.yaml),
#      TRAJECTORY_RATE (the config's trajectory.rate_hz: TRAJECTORY publications per second, 0 = every update),
#      COALESCE=0 (the graph stage takes every odometry message through its queue),
#      SAMPLES (a CSV file: every message's latencies), IDLE=1 (the baseline: no background graph, optimizer idle),
#      KEEP=1 (keep the work folder with the daemon's log),
#      INERTIAL=1 (the body has an IMU at RATE, odometry with its twist at RATE/20 and GNSS at RATE/200; CONFIG defaults
#      to bench/latency/inertial.yaml, the optimizer idle as with IDLE=1; FUSED_POSE is the inertial filter's).
# Prints: the 1-minute load average before and after; per channel (FUSED_POSE = the EKF, FUSED_POSE_GRAPH = the
# graph's pose, FUSED_POSE_DEAD_RECKONING, LATENCY_PONG = the raw round trip) samples, lost, p50/p99/max in ms and
# the daemon/raw ratios; the optimizer during the measurement: keyframes and loops (total and per minute), solve
# times, the graph stage's queue depth, events dropped per stage, odometry coalesced, the graph stage's own lag.
# Exit 0 on a complete run, 1 when a channel stayed silent or the optimizer did not run, 2 on bad arguments.
set -euo pipefail
usage() { sed -n '/^# Usage:/,/^# Exit/p' "$0" | sed 's/^# \{0,1\}//'; }
case "${1:-}" in -h|--help) usage; exit 0 ;; "") usage >&2; exit 2 ;; esac
build=$1
json=${2:+$(realpath -m "$2")}
samples=${SAMPLES:+$(realpath -m "$SAMPLES")}
root=$(cd "$(dirname "$0")/../.." && pwd)
[[ $build = /* ]] || build="$root/$build"
bin="$build/bin"
for b in sextantd sextant daemon_latency; do
  [ -x "$bin/$b" ] || { echo "run.sh: $bin/$b missing; build it first (see --help):" >&2; usage | sed -n '2,4p' >&2; exit 2; }
done
source "$root/tests/e2e/netns.bash"
require_netns
graph=${GRAPH:-$root/../shared/data/posegraph/city10000.g2o}
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT
config="$work/daemon.yaml"
sed -e "${TRAJECTORY_RATE:+s/rate_hz: [0-9.]*/rate_hz: $TRAJECTORY_RATE/}" \
    -e "${COALESCE:+s/coalesce_odometry: [a-z]*/coalesce_odometry: $([ "$COALESCE" = 0 ] && echo false || echo true)/}" \
    "${CONFIG:-$root/bench/latency/$([ -n "${INERTIAL:-}" ] && echo inertial || echo daemon).yaml}" > "$config"

feed="--idle${INERTIAL:+ --inertial --expect FUSED_POSE}"
if [ -z "${IDLE:-}" ] && [ -z "${INERTIAL:-}" ]; then
  "$bin/sextant" convert g2o "$graph" -o "$work/graph.lcm" > /dev/null
  feed="--feed $work/graph.lcm"
fi
cat > "$work/inside.sh" <<EOS
set -euo pipefail
"$bin/sextantd" --config "$config" > "$work/daemon.log" 2>&1 &
daemon=\$!
"$bin/daemon_latency" echo > "$work/echo.log" 2>&1 &
echo=\$!
sleep 0.7
if ! kill -0 \$daemon 2> /dev/null; then echo "sextantd exited at start:"; tail -20 "$work/daemon.log"; exit 1; fi
rc=0
"$bin/daemon_latency" measure $feed --duration ${DURATION:-60} --rate ${RATE:-1000} \
    --window ${WINDOW:-4} --feed-rate ${FEED_RATE:-1000} ${json:+--json "$json"} ${samples:+--samples "$samples"} || rc=\$?
kill -TERM \$echo; wait \$echo || true
kill -TERM \$daemon
drc=0; wait \$daemon || drc=\$?
if [ \$drc -ne 0 ]; then echo "sextantd exited with \$drc:"; tail -20 "$work/daemon.log"; exit 1; fi
exit \$rc
EOS
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
rc=0
in_netns bash "$work/inside.sh" || rc=$?
echo "load average after:  $(cut -d' ' -f1-3 /proc/loadavg)"
exit $rc
