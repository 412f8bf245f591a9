#!/usr/bin/env bash
# make demo: a simulated run fed to sextantd over LCM, watched live, then replayed offline into files.
# Runs inside a private network namespace when it can (nothing leaves the machine, no host route needed).
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/$build/bin"
out="$root/out/demo"
mkdir -p "$out"
rm -f "$out"/*.lcm

. "$root/scripts/demo_world.sh"
config="$out/config.yaml"
demo_config "$root/config/default.yaml" "$config"

echo "== 1. simulating a planar run: robot laps, landmarks, 4 passive sensors watching 4 targets (with false alarms"
echo "      in their fields of view over the targets' region), loop closures"
"$bin/sextant" simulate planar -o "$out/run.lcm" --seed 1 --duration 50 --tum-out "$out/ground_truth.txt" \
  --clutter "$false_alarms" --clutter-region "${region_min[@]}" "${region_max[@]}"

cat > "$out/live.sh" <<EOS
set -euo pipefail
"$bin/sextantd" --config "$config" --record "$out/received.lcm" --log-level warn &
daemon=\$!
lcm-logger -f "$out/bus.lcm" > /dev/null 2>&1 &
logger=\$!
"$bin/sextant" watch &
watcher=\$!
sleep 1
lcm-logplayer -s 2.5 "$out/run.lcm" > /dev/null
sleep 1.5
kill -TERM \$daemon; wait \$daemon
sleep 0.3
kill -TERM \$watcher; wait \$watcher || true
kill -INT \$logger; wait \$logger || true
EOS

echo "== 2. sextantd on the LCM bus, fed by lcm-logplayer (2.5x speed), recorded by lcm-logger; live view:"
if unshare --net true 2>/dev/null; then
  export LCM_DEFAULT_URL="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
  unshare --net bash -c 'ip link set lo up && ip route add 224.0.0.0/4 dev lo && exec bash "$0"' "$out/live.sh"
elif ip route get 239.255.76.67 > /dev/null 2>&1; then
  bash "$out/live.sh"
else
  echo "demo: no multicast route and no private network namespace available." >&2
  echo "      sudo ip route add 224.0.0.0/4 dev lo, or run make demo as root." >&2
  exit 1
fi

echo "== 3. the same run replayed offline (deterministic)"
"$bin/sextant" replay "$out/run.lcm" --config "$config" --tum-out "$out/estimate_tum.txt" \
  --kitti-out "$out/estimate_kitti.txt" --g2o-out "$out/estimate.g2o" --out-log "$out/replayed.lcm" \
  --report "$out/report" --json > "$out/replay.json"
echo "replay summary: $out/replay.json"
"$bin/sextant" eval --gt "$out/ground_truth.txt" --est "$out/estimate_tum.txt"

echo "== summary"
echo "  simulated run:          $out/run.lcm (ground truth $out/ground_truth.txt)"
echo "  what sextantd received: $out/received.lcm"
echo "  the whole bus:          $out/bus.lcm (lcm-logger)"
echo "  offline estimate:       $out/estimate_tum.txt (TUM), estimate_kitti.txt, estimate.g2o"
echo "  report:                 $out/report/index.html (plots), $out/report/report.json"
echo "  config:                 $config (config/default.yaml with the demo's association region)"
