#!/bin/bash
# Incremental smoother benchmark: `sextant optimize --incremental` on M3500, sphere2500, city10000 (RUNS
# runs each, default 3) and torus3D (TORUS_RUNS, default 1), with --relin-skip in SKIPS (default "1 10": ours and
# iSAM2's), one JSON per run in OUT, then a markdown table of the medians.
# With a second build directory BASE, every run of BUILD is followed by the same run of BASE (interleaved, so that
# both see the same machine load) and the table gets a BASE row and a new/base ratio row per data set.
# Usage: bench/incremental_smoother.sh [BUILD_DIR] [OUT_DIR] [BASE_BUILD_DIR]
#   e.g. SKIPS=1 bench/incremental_smoother.sh build /tmp/inc /work/wt-old/build
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$here/build}
out=${2:-$(mktemp -d)}
base=${3:-}
data=$here/../shared/data/posegraph
runs=${RUNS:-3}
mkdir -p "$out"
labels="new"
[ -n "$base" ] && labels="new base"
for ds in M3500 sphere2500 city10000 torus3D; do
  n=$runs
  [ "$ds" = torus3D ] && n=${TORUS_RUNS:-1}
  for skip in ${SKIPS:-1 10}; do
    for r in $(seq 1 "$n"); do
      for label in $labels; do
        bin=$build/bin/sextant
        [ "$label" = base ] && bin=$base/bin/sextant
        "$bin" optimize "$data/$ds.g2o" --incremental --relin-skip "$skip" --json > "$out/$ds.s$skip.$label.r$r.json"
        echo "$ds skip $skip run $r $label, load $(cut -d' ' -f1-3 /proc/loadavg)" >&2
      done
    done
  done
done
python3 - "$out" <<'PY'
import collections, glob, json, statistics, sys
rows = collections.defaultdict(list)
for f in sorted(glob.glob(sys.argv[1] + '/*.json')):
    ds, skip, label = f.split('/')[-1].split('.')[:3]
    rows[(ds, skip[1:], label)].append(json.load(open(f)))
keys = ['step_ms_mean', 'step_ms_p50', 'step_ms_p99', 'step_ms_max', 'final_chi2_batch_ratio', 'rebuilds', 'peak_rss_mb']
print("| data set | relinearize skip | build | runs | step mean [ms] | p50 | p99 | max | final chi2 / batch | rebuilds | peak RSS [MB] |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for (ds, skip, label), runs in sorted(rows.items(), key=lambda kv: (kv[0][0], kv[0][1], kv[0][2] != 'new')):
    m = {k: statistics.median(d[k] for d in runs) for k in keys}
    print(f"| {ds} | {skip} | {label} | {len(runs)} | {m['step_ms_mean']:.3f} | {m['step_ms_p50']:.3f} | {m['step_ms_p99']:.2f} | "
          f"{m['step_ms_max']:.1f} | {m['final_chi2_batch_ratio']:.7f} | {m['rebuilds']:.0f} | {m['peak_rss_mb']:.1f} |")
    if label == 'base' and (ds, skip, 'new') in rows:
        new = rows[(ds, skip, 'new')]
        r = lambda k: statistics.median(d[k] for d in new) / m[k]
        print(f"| {ds} | {skip} | new / base | | {r('step_ms_mean'):.2f} | {r('step_ms_p50'):.2f} | {r('step_ms_p99'):.2f} | "
              f"{r('step_ms_max'):.2f} | | | {r('peak_rss_mb'):.2f} |")
PY
