#!/usr/bin/env bash
# A fleet of daemons across hosts: three test hosts (network namespaces on one bridge), one robot each; each host's
# sextantd is fed only its own robot's sensors (a simulated planar fleet split per robot, channels prefixed
# ROBOTn_) and exchanges graph contributions with the others over LCM (FLEET, FLEET_CONTROL).  Every host drops 10 %
# of the datagrams it receives, host 2 (its daemon and its robot) starts 3 s after the others and takes their history
# by repair, and host 3's link is cut for 8 s in the middle of the run.  Meanwhile host 1's daemon is killed (SIGKILL:
# no final save) 3.5 s after one of its periodic saves, its robot's log held while it is down, and restarted on its
# state directory: it takes back from host 2 what it sent since that save.  After the run, every
# daemon's view of every robot (its TRAJECTORY) must be the single daemon's (`sextant replay` of the whole fleet)
# within 1 cm RMS with no keyframe missing, all in one map frame; host 1 took its tail back and no daemon saw a
# stream rewound.
set -euo pipefail
source "$(dirname "$0")/netns.bash"
require_netns
if ! command -v nft > /dev/null || ! unshare --net --mount true 2> /dev/null; then
  echo "SKIP: needs nftables and mount namespaces" >&2
  exit 77
fi
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT
e2e=$(cd "$(dirname "$0")" && pwd)

"$SEXTANT_BIN/sextant" simulate planar --robots 3 --duration 60 --seed 4 --loop-distance 0 -o "$work/sim.lcm" \
  --config-out "$work/fleet.yaml" > /dev/null
markers=$(grep markers "$work/fleet.yaml" | sed 's/^ *//')
python3 "$e2e/split_fleet_log.py" "$work/sim.lcm" "$work" robot1=ROBOT1_ robot2=ROBOT2_ robot3=ROBOT3_

config() {  # config NAME PREFIX EXCHANGE [STATE_DIR]
  cat <<EOC
daemon:
  name: $1
  status_period_s: 0.5
  state_dir: "${4:-}"
  state_period_s: 5.0
channels:
  prefix: "$2"
engine:
  primary_estimator: graph
  graph:
    fleet:
      enabled: true
      $markers
      exchange:
        enabled: $3
        members: [host1, host2, host3]
EOC
}
config single "" false > "$work/single.yaml"
config host1 ROBOT1_ true "$work/state1" > "$work/host1.yaml"
for n in 2 3; do config "host$n" "ROBOT${n}_" true > "$work/host$n.yaml"; done
"$SEXTANT_BIN/sextant" replay "$work/sim.lcm" --config "$work/single.yaml" --out-log "$work/single_out.lcm" \
  > /dev/null

cat > "$work/lab.sh" <<EOS
set -euo pipefail
source "$e2e/fleet_lab.bash"
trap 'kill \$(jobs -p) 2> /dev/null || true' EXIT
lab_init
for n in 1 2 3; do lab_host \$n; lab_loss \$n 10; done
start_daemon() {  # start_daemon N LOG: host N's daemon, waited for
  local n=\$1 log=\$2
  in_host \$n "$SEXTANT_BIN/sextantd" --config "$work/host\$n.yaml" > "\$log" 2>&1 &
  daemons[\$n]=\$!
  until grep -q "running on" "\$log" 2> /dev/null; do
    kill -0 \${daemons[\$n]} || { cat "\$log"; exit 1; }
    sleep 0.1
  done
}
start_host() {  # its logger, its daemon, then its robot's log
  local n=\$1
  in_host \$n lcm-logger -f "$work/bus\$n.lcm" --channel="ROBOT\${n}_.*" > /dev/null 2>&1 &
  loggers[\$n]=\$!
  start_daemon \$n "$work/daemon\$n.log"
  sleep 0.3
  in_host \$n lcm-logplayer -s 4 "$work/robot\$n.lcm" > /dev/null &
  players[\$n]=\$!
}
restart_host1() {  # killed 3.5 s after a periodic save (its robot held meanwhile), restarted on its state directory
  touch "$work/mark"
  until [ "$work/state1/sextantd.state" -nt "$work/mark" ]; do sleep 0.05; done
  sleep 1
  # (On a slow machine the robot's log may have ended already: then nothing is held, nothing is lost.)
  kill -STOP \${players[1]} 2> /dev/null || true
  # What the robot sent is handled and contributed, and host 2 has repaired what it lost of it (a heartbeat shows a
  # lost tail), before the kill: a contribution no other daemon holds cannot be taken back.
  sleep 2.5
  kill -KILL \${daemons[1]}
  wait \${daemons[1]} || true
  start_daemon 1 "$work/daemon1_restarted.log"
  kill -CONT \${players[1]} 2> /dev/null || true
}
mkdir -p "$work/state1"
start_host 1; start_host 3
sleep 3; start_host 2  # robot 2 joins late: its daemon takes the others' history by repair
(sleep 1; lab_cut 3; sleep 8; lab_heal 3) &
cut=\$!
restart_host1  # while host 3 is cut off: only host 2 holds host 1's tail
wait \$cut
for n in 1 2 3; do wait \${players[\$n]}; done
sleep 10  # repairs after the heal and the last heartbeats
rc=0
for n in 1 2 3; do kill -TERM \${daemons[\$n]}; done
for n in 1 2 3; do wait \${daemons[\$n]} || { echo "sextantd on host \$n failed"; cat "$work/daemon\$n.log"; rc=1; }; done
sleep 0.3
for n in 1 2 3; do kill -INT \${loggers[\$n]}; wait \${loggers[\$n]} || true; done
exit \$rc
EOS
unshare --net --mount bash "$work/lab.sh"
python3 "$e2e/check_fleet_hosts.py" --restarted host1 "$work/single_out.lcm" 0.01 host1="$work/bus1.lcm" \
  host2="$work/bus2.lcm" host3="$work/bus3.lcm"
echo "fleet_hosts: ok"
