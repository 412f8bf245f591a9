#!/usr/bin/env bash
# `sextant replay --tum-out F --body NAME` on a log of two robots: the file holds that robot's fused poses only, in
# time order (without --body both robots' poses interleave, at the same stamps); the two robots' files together are
# every pose of the unfiltered file, line for line; an unknown body exports nothing.
set -euo pipefail
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT
sextant="$SEXTANT_BIN/sextant"
"$sextant" simulate planar --robots 2 --duration 20 --seed 3 -o "$work/fleet.lcm" --config-out "$work/markers.yaml" > /dev/null
for b in all robot1 robot2 nobody; do
  body=()
  [ "$b" = all ] || body=(--body "$b")
  "$sextant" replay "$work/fleet.lcm" --config "$work/markers.yaml" --estimator graph "${body[@]}" \
    --tum-out "$work/$b.txt" > /dev/null
done
python3 - "$work" <<'PY'
import sys
work = sys.argv[1]
lines = {b: open(f"{work}/{b}.txt").read().splitlines() for b in ("all", "robot1", "robot2", "nobody")}
stamps = {b: [float(l.split()[0]) for l in ls] for b, ls in lines.items()}
assert len(lines["robot1"]) > 100 and len(lines["robot2"]) > 100, {b: len(l) for b, l in lines.items()}
assert not lines["nobody"], "an unknown body exported poses"
for b in ("robot1", "robot2"):
    assert all(x < y for x, y in zip(stamps[b], stamps[b][1:])), f"{b}: stamps not increasing"
assert any(x >= y for x, y in zip(stamps["all"], stamps["all"][1:])), "the unfiltered file is not interleaved"
assert sorted(lines["robot1"] + lines["robot2"]) == sorted(lines["all"]), "the two bodies' files are not the whole"
print("replay --body: robot1 %d, robot2 %d of %d poses" % (len(lines["robot1"]), len(lines["robot2"]), len(lines["all"])))
PY
