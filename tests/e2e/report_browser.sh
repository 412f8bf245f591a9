#!/usr/bin/env bash
# The replay report in a real browser: a simulated run (with false alarms, so the association makes far ghosts) is
# replayed with --report, headless Chromium renders the page; the DOM must hold every kind of plot with data in it:
# the trajectory coloured by its error (several colours and a colour bar), ATE over time for every estimator with the
# primary's rmse/mean/median lines and std band, RPE over time for every estimator, the channel bars named by channel,
# the targets framed to the targets (not squeezed by the ghosts); the screenshot must not be blank.  The association
# curves of `assoc-sim --csv` render as SVG with their data too.
set -euo pipefail
browser=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$browser" ]; then
  echo "SKIP: Chromium is not installed and could not be (scripts/install-deps.sh installs the Debian package 'chromium')" >&2
  exit 77
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$SEXTANT_BIN/sextant" simulate planar -o "$work/run.lcm" --seed 2 --duration 20 --clutter 1 > /dev/null
printf 'engine:\n  primary_estimator: graph\n' > "$work/graph.yaml"  # the report's primary: the graph back end
"$SEXTANT_BIN/sextant" replay "$work/run.lcm" --config "$work/graph.yaml" --report "$work/report" > /dev/null
test -s "$work/report/index.html" && test -s "$work/report/report.json"
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking
       --disable-component-update --disable-sync --user-data-dir="$work/profile" --window-size=1400,2000)
timeout 120 "$browser" "${flags[@]}" --dump-dom "file://$work/report/index.html" > "$work/dom.html" 2> /dev/null
timeout 120 "$browser" "${flags[@]}" --screenshot="$work/shot.png" "file://$work/report/index.html" > /dev/null 2>&1
"$SEXTANT_BIN/sextant" assoc-sim --sensors 3 --targets 2 --spacing 0.5 --sweep-to 2 --step 0.5 --sigma-mrad 1 --runs 10 \
    --cost classic,kl --csv "$work/assoc.csv" > /dev/null
assoc_svg=$(ls "$work"/assoc_sigma*mrad.svg)
timeout 120 "$browser" "${flags[@]}" --dump-dom "file://$assoc_svg" > "$work/assoc_dom.html" 2> /dev/null
python3 - "$work/dom.html" "$work/report/report.json" "$work/assoc_dom.html" <<'EOP'
import json, re, sys
dom = open(sys.argv[1]).read()
report = json.load(open(sys.argv[2]))
svgs = re.findall(r"<svg[^>]*class=\"plot\".*?</svg>", dom, re.S)
titles = [re.search(r"font-weight=\"bold\">([^<]*)<", s).group(1) for s in svgs]
plots = dict(zip(titles, svgs))
print("plots:", titles)
need = ["Top view", "Trajectory of graph coloured by its ATE (SE(3)-aligned)",
        "ATE over time, every estimator (SE(3)-aligned)", "RPE over time, every estimator (translation over 1 s)",
        "Targets (last 20 scans)", "Input messages per channel",
        "Processing time per event: dead_reckoning", "Processing time per event: filter",
        "Processing time per event: graph", "Processing time per event: graph_pose",
        "Processing time per event: association"]
missing = [t for t in need if t not in titles]
assert not missing, f"missing plots: {missing}"
def points(s):
    return sum(len(p.split()) for p in re.findall(r'class="series[^"]*" points="([^"]*)"', s))
for t, s in plots.items():
    assert len(re.findall(r'class="series', s)) > 0, f"plot '{t}' has no data"
estimators = sorted(report["estimators"])
assert len(estimators) >= 3, f"scores for {estimators} only"
assert points(plots["Top view"]) > 100
# coloured by the error: many runs in several colours, a colour bar
col = plots["Trajectory of graph coloured by its ATE (SE(3)-aligned)"]
colours = set(re.findall(r'stroke="(#[0-9a-f]{6})"[^>]*class="series colored"', col))
assert len(colours) >= 5 and 'class="colorbar"' in col and points(col) > 500, f"{len(colours)} colours"
# every estimator over time, with the primary's statistics
ate = plots["ATE over time, every estimator (SE(3)-aligned)"]
for name in estimators:
    assert f">{name}" in ate, f"no ATE curve of {name}"
    assert f">{name}" in plots["RPE over time, every estimator (translation over 1 s)"], f"no RPE curve of {name}"
assert len(re.findall(r'class="stat"', ate)) == 4, "rmse, mean, median lines and the std band"
rmse = report["estimators"]["graph"]["ate_rmse"]
assert f"graph rmse {rmse:.3f} m" in ate, "the rmse line's label"
assert points(ate) > 3 * 500
# channel bars named by their channels
cats = re.findall(r'class="category"[^>]*>([^<]*)<', plots["Input messages per channel"])
assert cats == sorted(report["channels"]), f"bar names {cats}"
# targets: framed to the truth, not squeezed by the ghosts (their spread covers a good part of the panel)
tg = plots["Targets (last 20 scans)"]
truth = [(float(x), float(y)) for x, y in re.findall(r'cx="([-0-9.]+)" cy="([-0-9.]+)" r="1.50" fill="#bbbbbb"', tg)]
assert len(truth) > 10, "no target truth"
width = max(x for x, _ in truth) - min(x for x, _ in truth)
assert width > 0.4 * (640 - 90), f"the targets' truth spans only {width:.0f} px of the panel"
assert "outside this frame" in dom, "the ghosts outside the frame are not mentioned"
assert "ATE (SE(3)-aligned" in dom, "no ATE line"
# assoc-sim's curves
adom = open(sys.argv[3]).read()
assert "Correct association rate" in adom and points(adom) >= 8, "assoc-sim's SVG has no curves"
EOP
read -r nonwhite total < <(python3 "$(dirname "$0")/png_pixels.py" "$work/shot.png")
echo "screenshot: $nonwhite of $total pixels not white"
python3 -c "import sys; n, t = $nonwhite, $total; sys.exit(0 if n > 0.03 * t else 1)" || { echo "the rendered page is blank"; exit 1; }
echo "report_browser: ok"
