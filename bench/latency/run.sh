#!/usr/bin/env bash
# sextantd's latency from an odometry message in to its FUSED_POSE out, over a real LCM bus (private network
# namespace), at 1 kHz while the graph back end works through city10000 in the background, next to the raw LCM
# round trip to a trivial echo measured in the same run (issue 4).  city10000 is converted with `sextant convert g2o`
# (its chain as the odometry of body 'robot1', its other edges as LOOP_CLOSURES) and fed by daemon_latency under flow
# control; the daemon runs bench/latency/daemon.yaml (every city10000 pose a keyframe).
# Usage: bench/latency/run.sh BUILD [JSON_OUT]   (BUILD: a build folder, relative to the project or absolute, built
#        with -DSEXTANT_BENCH=ON and the targets sextantd sextant daemon_latency)
# env: DURATION (60 s), RATE (1000 Hz), WINDOW (4 poses ahead of the optimizer), FEED_RATE (1000 poses/s),
#      GRAPH (city10000.g2o in ../shared/data/posegraph), CONFIG (bench/latency/daemon.yaml),
#      TRAJECTORY_KEYFRAMES (the config's trajectory_max_keyframes: keyframes per TRAJECTORY message),
#      SAMPLES (a CSV file: every message's latencies), IDLE=1 (the baseline: no background graph, optimizer idle)
set -euo pipefail
build=${1:?usage: bench/latency/run.sh BUILD [JSON_OUT]}
json=${2:+$(realpath -m "$2")}
samples=${SAMPLES:+$(realpath -m "$SAMPLES")}
root=$(cd "$(dirname "$0")/../.." && pwd)
[[ $build = /* ]] || build="$root/$build"
bin="$build/bin"
for b in sextantd sextant daemon_latency; do
  [ -x "$bin/$b" ] || { echo "run.sh: $bin/$b missing (configure with -DSEXTANT_BENCH=ON, build sextantd sextant daemon_latency)" >&2; exit 2; }
done
source "$root/tests/e2e/netns.bash"
require_netns
graph=${GRAPH:-$root/../shared/data/posegraph/city10000.g2o}
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT
config="$work/daemon.yaml"
sed "${TRAJECTORY_KEYFRAMES:+s/trajectory_max_keyframes: [0-9]*/trajectory_max_keyframes: $TRAJECTORY_KEYFRAMES/}" \
    "${CONFIG:-$root/bench/latency/daemon.yaml}" > "$config"

feed="--idle"
if [ -z "${IDLE:-}" ]; then
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
