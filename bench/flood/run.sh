#!/usr/bin/env bash
# sextantd with its default configuration, over a real LCM bus (private network namespace), following one robot at
# 50 Hz while a sender floods it with 60,000 one-off body names (2,000 messages/s for 60 s) and then 100,000
# impossible loop closures (2,000/s for 50 s); bench/flood/flood.py says what is sent.  Measures, per phase, the
# robot's poses and their latency (odometry arrival to FUSED_POSE arrival, both as lcm-logger received them) and the
# daemon's RSS, and prints the daemon's final counters (names refused and evicted, loops dropped).
#
# Usage: bench/flood/run.sh BUILD [JSON_OUT]
#   BUILD     a build folder (relative to the project or absolute) with sextantd (make build gives build/)
#   JSON_OUT  optional: the figures as JSON
# Needs root (or user namespaces) for `unshare --net`; takes about 3 minutes.
# env: CONFIG (config/default.yaml), BASELINE=1 (the robot alone: no flood), KEEP=1 (keep the work folder: the bus recording, the daemon's log, the RSS).
set -euo pipefail
usage() { sed -n '/^# Usage:/,/^# env/p' "$0" | sed 's/^# \{0,1\}//'; }
case "${1:-}" in -h|--help) usage; exit 0 ;; "") usage >&2; exit 2 ;; esac
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$1
[[ $build = /* ]] || build="$root/$build"
json=${2:+$(realpath -m "$2")}
[ -x "$build/bin/sextantd" ] || { echo "run.sh: $build/bin/sextantd missing (make build)" >&2; exit 2; }
export SEXTANT_LCMTYPES_PY="$build/lcmtypes/python"
source "$root/tests/e2e/netns.bash"
require_netns
config=${CONFIG:-$root/config/default.yaml}
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT
echo "work dir: $work"

# The robot's clock starts now: the daemon compares live stamps with the wall clock.
python3 "$root/bench/flood/flood.py" make "$work/flood.lcm" "$(date +%s%6N)" ${BASELINE:+robot-only}
cat > "$work/inside.sh" <<EOS
set -euo pipefail
source "$root/tests/e2e/netns.bash"
lcm-logger -f "$work/bus.lcm" > /dev/null 2>&1 &
logger=\$!
"$build/bin/sextantd" --config "$config" --log-level info > "$work/daemon.log" 2>&1 &
daemon=\$!
wait_running \$daemon "$work/daemon.log" || { kill -INT \$logger; exit 1; }
t0=\$(date +%s%N)
( while kill -0 \$daemon 2>/dev/null; do
    echo "\$(( (\$(date +%s%N) - t0) / 1000 )) \$(awk '/VmRSS/ {print \$2}' /proc/\$daemon/status)"; sleep 0.2
  done ) > "$work/rss.txt" 2>/dev/null &
sampler=\$!
lcm-logplayer "$work/flood.lcm"
sleep 2
kill -0 \$daemon || { echo "sextantd died"; tail -20 "$work/daemon.log"; exit 1; }
kill -TERM \$daemon
wait \$daemon || { echo "sextantd exited with \$?"; tail -20 "$work/daemon.log"; exit 1; }
sleep 0.3
kill -INT \$logger; wait \$logger || true
wait \$sampler || true
EOS
in_netns bash "$work/inside.sh"
python3 "$root/bench/flood/flood.py" summarize "$work/bus.lcm" "$work/rss.txt" $json
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
