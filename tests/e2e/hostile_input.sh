#!/usr/bin/env bash
# sextantd against a hostile sender, over a real LCM bus in a private network namespace (hostile_input.py says
# what is sent): the daemon must stay up (it used to abort on one 20-byte packet), refuse and count every hostile
# message by channel and reason, keep its memory bounded, follow the robot past the far-future stamps, count the
# sequence gaps as lost, and exit 0 on SIGTERM.  --record onto an existing file must keep that file.
# The checks that need no bus run first, also where no network namespace can be made: configs that cannot work exit
# 2 with FILE:LINE (a non-scalar key aborted sextantd), `sextant replay` of a damaged log says so and exits 4 unless
# --tolerate-damage (so do `replay --realtime` and `matcher --truth`), a 52-byte log claiming 2 GiB does not crash it,
# and --record keeps an existing file (memq://).
set -euo pipefail
source "$(dirname "$0")/netns.bash"
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT; echo "work dir: $work"

python3 "$here/hostile_input.py" make "$work/hostile.lcm"
printf 'daemon:\n  status_period_s: 0.2\nengine:\n  primary_estimator: dead_reckoning\n  filter:\n    type: none\n  graph:\n    enabled: false\n  association:\n    enabled: false\n' > "$work/config.yaml"

# First the checks that need no bus, so that they run wherever the test does (without network namespaces too).
# Configs that cannot work: exit 2 naming FILE:LINE (no bus needed: they fail before LCM starts).
check_config_error() {  # YAML EXPECTED_PREFIX
  printf "$1" > "$work/bad.yaml"
  local rc=0
  "$SEXTANT_BIN/sextantd" --config "$work/bad.yaml" > "$work/bad.log" 2>&1 || rc=$?
  [ "$rc" -eq 2 ] || { echo "FAIL: sextantd exited $rc on: $1"; cat "$work/bad.log"; exit 1; }
  grep -q "$work/bad.yaml:$2" "$work/bad.log" || { echo "FAIL: no $2 in:"; cat "$work/bad.log"; exit 1; }
}
check_config_error '[a]: 1\n' '1:1'
check_config_error 'channels:\n  prefix: PPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPPP\n' '2:'
check_config_error 'channels:\n  landmarks: ODOMETRY\n' '2:'
check_config_error 'channels:\n  fused_pose: LOOP_CLOSURES\n' '2:'

# A damaged log: replay goes on past the damage, reports it, and exits 4 unless told to tolerate it.
python3 - "$work/hostile.lcm" "$work/damaged.lcm" <<'EOP'
import struct, sys
b = bytearray(open(sys.argv[1], "rb").read())
pos, n = 0, 0
while n < 40:  # the data length of the 40th event
    clen, dlen = struct.unpack_from(">ii", b, pos + 20)
    pos += 28 + clen + dlen; n += 1
b[pos + 24:pos + 28] = struct.pack(">i", 1 << 24)
open(sys.argv[2], "wb").write(b)
EOP
rc=0; "$SEXTANT_BIN/sextant" replay "$work/damaged.lcm" --config "$work/config.yaml" > "$work/replay.out" 2> "$work/replay.err" || rc=$?
[ "$rc" -eq 4 ] || { echo "FAIL: replay of a damaged log exited $rc"; cat "$work/replay.err"; exit 1; }
grep -q "1 corrupt event header(s)" "$work/replay.err" || { echo "FAIL: damage not reported"; cat "$work/replay.err"; exit 1; }
"$SEXTANT_BIN/sextant" replay "$work/damaged.lcm" --config "$work/config.yaml" --tolerate-damage --json > "$work/replay.json"
python3 - "$work/replay.json" <<'EOP'
import json, sys
r = json.load(open(sys.argv[1]))
assert r["log_damage"]["corrupt_events"] == 1, r["log_damage"]
assert r["records"] > 300, r["records"]  # the events after the damage were replayed
print("replay of the damaged log:", r["records"], "events,", r["log_damage"])
EOP
# The other commands that read a log say so too, naming it, and exit 4 unless --tolerate-damage: republishing it
# (--realtime) and the simulated matcher's truth: a simulated run, damaged the same way (the hostile log's far-future
# stamps would make a real-time replay wait for years).
check_damage_reported() {  # WHAT LOG CMD...: exit 4 and the log named with its damage on stderr
  local what=$1 log=$2 rc=0
  shift 2
  "$@" > "$work/other.out" 2> "$work/other.err" || rc=$?
  [ "$rc" -eq 4 ] || { echo "FAIL: $what of a damaged log exited $rc"; cat "$work/other.err"; exit 1; }
  grep -q "$log: 1 corrupt event header(s)" "$work/other.err" || { echo "FAIL: $what: damage not reported"; cat "$work/other.err"; exit 1; }
}
"$SEXTANT_BIN/sextant" simulate planar -o "$work/sim.lcm" --duration 10 > /dev/null
python3 - "$work/sim.lcm" "$work/sim-damaged.lcm" <<'EOP'
import struct, sys
b = bytearray(open(sys.argv[1], "rb").read())
pos, n = 0, 0
while n < 40:
    clen, dlen = struct.unpack_from(">ii", b, pos + 20)
    pos += 28 + clen + dlen; n += 1
b[pos + 24:pos + 28] = struct.pack(">i", 1 << 24)
open(sys.argv[2], "wb").write(b)
EOP
check_damage_reported "replay --realtime" "$work/sim-damaged.lcm" \
  "$SEXTANT_BIN/sextant" replay "$work/sim-damaged.lcm" --realtime --speed 1000 --lcm-url memq://
"$SEXTANT_BIN/sextant" replay "$work/sim-damaged.lcm" --realtime --speed 1000 --lcm-url memq:// --tolerate-damage > /dev/null 2>&1 \
  || { echo "FAIL: replay --realtime --tolerate-damage of a damaged log failed"; exit 1; }
check_damage_reported "matcher --truth" "$work/sim-damaged.lcm" \
  "$SEXTANT_BIN/sextant" matcher --truth "$work/sim-damaged.lcm" --lcm-url memq:// --seconds 0.1
"$SEXTANT_BIN/sextant" matcher --truth "$work/sim-damaged.lcm" --lcm-url memq:// --seconds 0.1 --tolerate-damage \
  > /dev/null 2>&1 || { echo "FAIL: matcher --tolerate-damage on a damaged truth log failed"; exit 1; }
"$SEXTANT_BIN/sextant" matcher --truth "$work/sim.lcm" --lcm-url memq:// --seconds 0.1 > /dev/null 2> "$work/clean.err" \
  || { echo "FAIL: matcher on a clean truth log failed"; cat "$work/clean.err"; exit 1; }
[ ! -s "$work/clean.err" ] || { echo "FAIL: matcher warned on a clean log"; cat "$work/clean.err"; exit 1; }
# A 52-byte log whose only event claims 2 GiB of data: no crash (liblcm's reader segfaulted).
python3 -c "import struct,sys; open(sys.argv[1],'wb').write(struct.pack('>Iqqii',0xEDA1DA01,0,0,4,0x7fffffff)+b'ODOM'+bytes(20))" "$work/52.lcm"
"$SEXTANT_BIN/sextant" replay "$work/52.lcm" --config "$work/config.yaml" > /dev/null 2> "$work/52.err"
grep -q "last event truncated" "$work/52.err" || { echo "FAIL: truncation not reported"; cat "$work/52.err"; exit 1; }
# --record onto an existing file keeps it, over LCM's in-process provider (the daemon records its own status).
echo "an earlier recording" > "$work/memq.lcm"
"$SEXTANT_BIN/sextantd" --config "$work/config.yaml" --lcm-url memq:// --record "$work/memq.lcm" --log-level info \
  > "$work/memq.log" 2>&1 &
daemon=$!
wait_running $daemon "$work/memq.log" || exit 1
sleep 0.5
kill -TERM $daemon
wait $daemon || { echo "FAIL: sextantd (memq://) exited with $?"; cat "$work/memq.log"; exit 1; }
[ "$(cat "$work/memq.lcm")" = "an earlier recording" ] || { echo "FAIL: --record overwrote $work/memq.lcm"; exit 1; }
[ -s "$work/memq-1.lcm" ] || { echo "FAIL: no recording in $work/memq-1.lcm"; cat "$work/memq.log"; exit 1; }
grep -q "memq.lcm exists and is kept; recording to .*memq-1.lcm" "$work/memq.log" || { echo "FAIL: --record said nothing"; exit 1; }
echo "hostile_input: the checks without a bus passed"

# Then the hostile sender on a real bus.
require_netns
echo "an earlier recording" > "$work/rec.lcm"
cat > "$work/run.sh" <<EOS
set -euo pipefail
source "$here/netns.bash"
lcm-logger -f "$work/bus.lcm" > /dev/null 2>&1 &
logger=\$!
"$SEXTANT_BIN/sextantd" --config "$work/config.yaml" --record "$work/rec.lcm" --log-level info > "$work/daemon.log" 2>&1 &
daemon=\$!
wait_running \$daemon "$work/daemon.log" || { kill -INT \$logger; exit 1; }
sleep 0.2
( while kill -0 \$daemon 2>/dev/null; do grep VmRSS /proc/\$daemon/status | awk '{print \$2}'; sleep 0.1; done ) > "$work/rss.txt" &
sampler=\$!
lcm-logplayer -s 2 "$work/hostile.lcm"
sleep 0.8
kill -0 \$daemon || { echo "sextantd died"; cat "$work/daemon.log"; exit 1; }
kill -TERM \$daemon
wait \$daemon || { echo "sextantd exited with \$?"; cat "$work/daemon.log"; exit 1; }
sleep 0.3
kill -INT \$logger; wait \$logger || true
wait \$sampler || true
EOS
in_netns bash "$work/run.sh"
python3 "$here/hostile_input.py" check "$work/bus.lcm"

# --record kept the earlier file and recorded next to it, and said so.
[ "$(cat "$work/rec.lcm")" = "an earlier recording" ] || { echo "FAIL: --record overwrote $work/rec.lcm"; exit 1; }
[ -s "$work/rec-1.lcm" ] || { echo "FAIL: no recording in $work/rec-1.lcm"; exit 1; }
grep -q "rec.lcm exists and is kept; recording to .*rec-1.lcm" "$work/daemon.log" || { echo "FAIL: --record said nothing"; exit 1; }

if [ -z "${ASAN_OPTIONS:-}" ]; then
  python3 - "$work/rss.txt" <<'EOP'
import sys
v = [int(x) for x in open(sys.argv[1]).read().split()]
print(f"RSS kB: start {v[0]} peak {max(v)}")
assert max(v) < 64 * 1024, f"peak RSS {max(v)} kB (20,000,000 landmark observations were allocated before)"
EOP
fi

echo "hostile_input: ok"
