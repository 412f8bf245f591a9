#!/usr/bin/env bash
# The replay report in a real browser: a simulated run is replayed with --report, headless Chromium renders the
# page; the DOM must hold the five kinds of plot with data in them, and the screenshot must not be blank.
set -euo pipefail
browser=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$browser" ]; then
  echo "SKIP: Chromium is not installed and could not be (scripts/install-deps.sh installs the Debian package 'chromium')" >&2
  exit 77
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$SEXTANT_BIN/sextant" simulate planar -o "$work/run.lcm" --seed 2 --duration 20 > /dev/null
printf 'engine:\n  primary_estimator: graph\n' > "$work/graph.yaml"  # the report's primary: the graph back end
"$SEXTANT_BIN/sextant" replay "$work/run.lcm" --config "$work/graph.yaml" --report "$work/report" > /dev/null
test -s "$work/report/index.html" && test -s "$work/report/report.json"
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking
       --disable-component-update --disable-sync --user-data-dir="$work/profile" --window-size=1400,2000)
timeout 120 "$browser" "${flags[@]}" --dump-dom "file://$work/report/index.html" > "$work/dom.html" 2> /dev/null
timeout 120 "$browser" "${flags[@]}" --screenshot="$work/shot.png" "file://$work/report/index.html" > /dev/null 2>&1
python3 - "$work/dom.html" <<'EOP'
import re, sys
dom = open(sys.argv[1]).read()
svgs = re.findall(r"<svg[^>]*class=\"plot\".*?</svg>", dom, re.S)
titles = [re.search(r"font-weight=\"bold\">([^<]*)<", s).group(1) for s in svgs]
print("plots:", titles)
need = ["Top view", "Position error of graph", "Targets (last 20 scans)", "Input messages per channel",
        "Processing time per event: dead_reckoning", "Processing time per event: filter",
        "Processing time per event: graph", "Processing time per event: graph_pose",
        "Processing time per event: association"]
missing = [t for t in need if t not in titles]
assert not missing, f"missing plots: {missing}"
for s, t in zip(svgs, titles):
    series = len(re.findall(r'class="series"', s))
    points = sum(len(p.split()) for p in re.findall(r'class="series" points="([^"]*)"', s))
    assert series > 0, f"plot '{t}' has no data"
    if t in ("Top view", "Position error of graph"):
        assert points > 100, f"plot '{t}' has only {points} points"
assert "ATE (SE(3)-aligned" in dom, "no ATE line"
EOP
read -r nonwhite total < <(python3 "$(dirname "$0")/png_pixels.py" "$work/shot.png")
echo "screenshot: $nonwhite of $total pixels not white"
python3 -c "import sys; n, t = $nonwhite, $total; sys.exit(0 if n > 0.03 * t else 1)" || { echo "the rendered page is blank"; exit 1; }
echo "report_browser: ok"
