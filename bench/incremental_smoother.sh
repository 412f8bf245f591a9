#!/bin/bash
# Incremental smoother benchmark of issue 4: `sextant optimize --incremental` on M3500, sphere2500, city10000 (RUNS
# runs each, default 3) and torus3D (one run), with --relin-skip 1 (the default) and 10 (iSAM2's), one JSON per run
# in OUT, then a markdown table of the medians.
# Usage: bench/incremental_smoother.sh [BUILD_DIR] [OUT_DIR]
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$here/build}
out=${2:-$(mktemp -d)}
data=$here/../shared/data/posegraph
runs=${RUNS:-3}
mkdir -p "$out"
for ds in M3500 sphere2500 city10000 torus3D; do
  n=$runs
  [ "$ds" = torus3D ] && n=1
  for skip in 1 10; do
    for r in $(seq 1 "$n"); do
      "$build/bin/sextant" optimize "$data/$ds.g2o" --incremental --relin-skip "$skip" --json > "$out/$ds.s$skip.r$r.json"
      echo "$ds skip $skip run $r, load $(cut -d' ' -f1-3 /proc/loadavg)" >&2
    done
  done
done
python3 - "$out" <<'PY'
import collections, glob, json, statistics, sys
rows = collections.defaultdict(list)
for f in sorted(glob.glob(sys.argv[1] + '/*.json')):
    ds, skip = f.split('/')[-1].split('.')[:2]
    rows[(ds, skip[1:])].append(json.load(open(f)))
print("| data set | relinearize skip | runs | step mean [ms] | p50 | p99 | max | final chi2 / batch | rebuilds | peak RSS [MB] |")
print("|---|---|---|---|---|---|---|---|---|---|")
for (ds, skip), runs in rows.items():
    m = lambda k: statistics.median(d[k] for d in runs)
    print(f"| {ds} | {skip} | {len(runs)} | {m('step_ms_mean'):.3f} | {m('step_ms_p50'):.3f} | {m('step_ms_p99'):.2f} | "
          f"{m('step_ms_max'):.1f} | {m('final_chi2_batch_ratio'):.7f} | {m('rebuilds'):.0f} | {m('peak_rss_mb'):.0f} |")
PY
