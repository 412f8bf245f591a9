#!/usr/bin/env bash
# The README's Foxglove screenshot (docs/img/foxglove.png): a simulated three-robot fleet played on a private LCM bus
# to sextantd, `sextant foxglove` bridging it, and Foxglove Studio's open-source web build (@foxglove/studio-base
# 1.48.0, MPL-2.0, the code base Lichtblick forked; scripts/foxglove_screenshot/, npm packages pinned by its
# package-lock.json) in headless Chromium (Debian's chromium, driven by playwright-core) connected to
# ws://127.0.0.1:8765, its 3-D panel captured near the end of the run.  Not part of `make test`: it takes about a
# minute and needs chromium; it is a picture, not a check.  (Lichtblick's npm package @lichtblick/suite is its
# extension API's types only, no app; studio-base ships the whole app prebuilt, so nothing is built here.)
#
# Usage: scripts/foxglove_screenshot.sh [BUILD] [OUT.png]      (BUILD: build; OUT: docs/img/foxglove.png)
# A file instead: node scripts/foxglove_screenshot/shot.mjs FILE.mcap OUT.png --time RFC3339 (Foxglove's remote-file
# source over a local HTTP server, seeked to that time).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
here="$root/scripts/foxglove_screenshot"
source "$root/tests/e2e/netns.bash"

if [ "${1:-}" = --inside ]; then  # in the namespace: bridge, page, daemon, player
  work=$2 out=$3
  trap 'kill $(jobs -p) 2> /dev/null || true' EXIT
  "$SEXTANT_BIN/sextant" foxglove --port 8765 > "$work/bridge.log" 2>&1 &
  for _ in $(seq 100); do grep -q "serving on" "$work/bridge.log" && break; sleep 0.1; done
  "$SEXTANT_BIN/sextantd" --config "$work/fleet.yaml" > "$work/daemon.log" 2>&1 &
  daemon=$!
  wait_running "$daemon" "$work/daemon.log"
  # The page loads and connects in a few seconds; the run plays in 22 s (90 s at 4x); the picture is taken at 30 s.
  node "$here/shot.mjs" ws://127.0.0.1:8765 "$out" --wait 30 --log "$work/page.log" &
  shot=$!
  sleep 5
  lcm-logplayer -s 4 "$work/fleet.lcm" > /dev/null
  wait "$shot"
  exit 0
fi

export SEXTANT_BIN="$root/${1:-build}/bin"
out="$(realpath -m "${2:-$root/docs/img/foxglove.png}")"
command -v /usr/bin/chromium > /dev/null || { echo "needs Debian's chromium: apt-get install chromium" >&2; exit 1; }
"$root/scripts/install-node-deps.sh" "$here"
require_netns
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT
"$SEXTANT_BIN/sextant" simulate planar --robots 3 -o "$work/fleet.lcm" --seed 5 --duration 90 \
  --config-out "$work/fleet.yaml" > /dev/null
mkdir -p "$(dirname "$out")"
in_netns bash "$0" --inside "$work" "$out"
grep -c "pageerror" "$work/page.log" > /dev/null && { echo "errors in the page:"; grep pageerror "$work/page.log"; }
echo "foxglove_screenshot: $out"
