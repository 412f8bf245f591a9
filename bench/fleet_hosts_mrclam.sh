#!/usr/bin/env bash
# Five daemons, one per MRCLAM robot, each on its own test host (network namespaces on one bridge, as
# tests/e2e/fleet_hosts.sh), against one daemon fed every robot (`sextant replay` of the fleet log with
# config/mrclam_fleet.yaml).  Each host's sextantd hears only its robot's odometry and sightings (channels ROBOTn_)
# and exchanges graph contributions on FLEET / FLEET_CONTROL.  Every host drops LOSS % (default 10) of the datagrams
# it receives; host CUT_HOST (default 3) is cut off for CUT_S seconds (default 60, wall clock) from CUT_AT_S (default
# 20) after the start.  The 900 s of Dataset 7 are played at SPEED (default 10) times real time.
# Prints: every daemon's final view of every robot against the single daemon (RMS, missing keyframes); how long after
# the heal every daemon held every stream whole again (the status' fleet_in_held back to its usual level before the
# cut; fleet_in_lost); the fleet traffic (FLEET + FLEET_CONTROL bytes each daemon published) per robot per second of data, in
# each third of the run (no growth with the fleet's age).
# LIFELONG=0 turns the lifelong thinning off on every daemon (thinning is each daemon's own decision, see the notes).
# Usage: SEXTANT_BIN=build/bin SEXTANT_LCMTYPES_PY=build/lcmtypes/python bench/fleet_hosts_mrclam.sh OUT_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
e2e=$root/tests/e2e
source "$e2e/netns.bash"
require_netns
out=$(mkdir -p "$1" && cd "$1" && pwd)
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT
speed=${SPEED:-10} loss=${LOSS:-10} cut_host=${CUT_HOST:-3} cut_at=${CUT_AT_S:-20} cut_s=${CUT_S:-60}
data="$root/../shared/data/landmarks/MRCLAM_Dataset7"
"$SEXTANT_BIN/sextant" convert mrclam "$data" --robots 1-5 -o "$work/fleet.lcm" --gt-out "$work/gt_" > /dev/null
python3 "$e2e/split_fleet_log.py" "$work/fleet.lcm" "$work" robot1=ROBOT1_ robot2=ROBOT2_ robot3=ROBOT3_ \
  robot4=ROBOT4_ robot5=ROBOT5_ > /dev/null
thin=()
[ "${LIFELONG:-1}" = 0 ] && thin=(-e 's/^    fleet:$/    lifelong:\n      enabled: false\n    fleet:/')
for n in 1 2 3 4 5; do
  sed "${thin[@]}" -e "s/name: sextantd-mrclam-fleet/name: host$n/" -e "s/prefix: \"\" .*/prefix: \"ROBOT${n}_\"/" \
    -e "s/^\( *\)markers: \(.*\)/\1markers: \2\n\1exchange:\n\1  enabled: true\n\1  members: [host1, host2, host3, host4, host5]/" \
    "$root/config/mrclam_fleet.yaml" > "$work/host$n.yaml"
done
sed "${thin[@]}" -e "s/name: sextantd-mrclam-fleet/name: single/" "$root/config/mrclam_fleet.yaml" > "$work/single.yaml"
"$SEXTANT_BIN/sextant" replay "$work/fleet.lcm" --config "$work/single.yaml" --out-log "$work/single_out.lcm" > /dev/null

cat > "$work/lab.sh" <<EOS
set -euo pipefail
source "$e2e/fleet_lab.bash"
trap 'kill \$(jobs -p) 2> /dev/null || true' EXIT
lab_init
for n in 1 2 3 4 5; do lab_host \$n; lab_loss \$n $loss; done
for n in 1 2 3 4 5; do
  in_host \$n lcm-logger -f "$work/bus\$n.lcm" --channel="ROBOT\${n}_.*" > /dev/null 2>&1 &
  loggers[\$n]=\$!
  in_host \$n "$SEXTANT_BIN/sextantd" --config "$work/host\$n.yaml" > "$work/daemon\$n.log" 2>&1 &
  daemons[\$n]=\$!
done
for n in 1 2 3 4 5; do
  until grep -q "running on" "$work/daemon\$n.log" 2> /dev/null; do
    kill -0 \${daemons[\$n]} || { cat "$work/daemon\$n.log"; exit 1; }
    sleep 0.1
  done
done
sleep 0.3
date +%s.%N > "$work/start"
for n in 1 2 3 4 5; do in_host \$n lcm-logplayer -s $speed "$work/robot\$n.lcm" > /dev/null & players[\$n]=\$!; done
sleep $cut_at; lab_cut $cut_host; date +%s.%N > "$work/cut"; sleep $cut_s; lab_heal $cut_host; date +%s.%N > "$work/healed"
for n in 1 2 3 4 5; do wait \${players[\$n]}; done
date +%s.%N > "$work/played"
sleep 20  # repairs after the heal and the last heartbeats
rc=0
for n in 1 2 3 4 5; do kill -TERM \${daemons[\$n]}; done
for n in 1 2 3 4 5; do wait \${daemons[\$n]} || { echo "sextantd on host \$n failed"; rc=1; }; done
sleep 0.3
for n in 1 2 3 4 5; do kill -INT \${loggers[\$n]}; wait \${loggers[\$n]} || true; done
exit \$rc
EOS
unshare --net --mount bash "$work/lab.sh"
{
  echo "## Five daemons on MRCLAM Dataset 7 ($(git -C "$root" rev-parse --short HEAD), $(date -u +%F))"
  echo "speed ${speed}x, loss ${loss} % per host, host $cut_host cut ${cut_s} s from ${cut_at} s, lifelong ${LIFELONG:-1}"
  python3 "$e2e/check_fleet_hosts.py" "$work/single_out.lcm" 0.01 host1="$work/bus1.lcm" host2="$work/bus2.lcm" \
    host3="$work/bus3.lcm" host4="$work/bus4.lcm" host5="$work/bus5.lcm" || true
  echo "### every daemon against the owner of robot1's (host1's) view"
  python3 "$e2e/check_fleet_hosts.py" "$work/bus1.lcm" 0.01 host2="$work/bus2.lcm" host3="$work/bus3.lcm" \
    host4="$work/bus4.lcm" host5="$work/bus5.lcm" || true
  PYTHONPATH="$e2e:$SEXTANT_LCMTYPES_PY" python3 "$root/bench/fleet_hosts_summary.py" "$work" 900 5
} | tee "$out/fleet_hosts_mrclam.md"
