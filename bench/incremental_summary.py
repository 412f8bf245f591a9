#!/usr/bin/env python3
"""Summary of bench/incremental_smoother.sh: per data set the medians over rounds of sextant (new, and base when
run) and of iSAM2, then the same-run ratios sextant / iSAM2 and new / base.  final chi2 / batch divides each
solver's final chi2 by sextant's batch Gauss-Newton solve of the same graph from the same start (in sextant's JSON).
Usage: incremental_summary.py OUT_DIR"""
import collections
import glob
import json
import os
import statistics
import sys

out = sys.argv[1]
runs = collections.defaultdict(list)  # (data set, label) -> JSON of each round; label: "new s1", "base s1", "iSAM2"
for f in sorted(glob.glob(os.path.join(out, '*.json'))):
    parts = os.path.basename(f).split('.')
    ds = parts[0]
    label = 'iSAM2' if parts[1] == 'isam2' else f'{parts[2]} (skip {parts[1][1:]})'
    if os.path.getsize(f) == 0:  # a run that failed (or is still running) left no JSON
        print(f'skipped {f}: empty', file=sys.stderr)
        continue
    runs[(ds, label)].append(json.load(open(f)))

batch = {}
for (ds, label), rs in runs.items():
    if label != 'iSAM2':
        batch[ds] = statistics.median(r['batch_final_chi2'] for r in rs)


def med(rs, key):
    return statistics.median(r[key] for r in rs)


keys = ['step_ms_mean', 'step_ms_p50', 'step_ms_p99', 'step_ms_max']
if os.path.exists(os.path.join(out, 'PEER_NOT_BUILT')):
    print('**iSAM2 peer not built: no ratios to iSAM2 in this run.**\n')
print('| data set | solver | rounds | step mean [ms] | p50 | p99 | max | final chi2 | final chi2 / batch - 1 | '
      'rebuilds | peak RSS [MB] |')
print('|---|---|---|---|---|---|---|---|---|---|---|')
for ds in sorted({k[0] for k in runs}):
    labels = sorted((k[1] for k in runs if k[0] == ds), key=lambda l: (l == 'iSAM2', not l.startswith('new'), l))
    for label in labels:
        rs = runs[(ds, label)]
        chi2 = med(rs, 'final_chi2')
        rel = f'{chi2 / batch[ds] - 1:.1e}' if ds in batch else ''
        rebuilds = f"{med(rs, 'rebuilds'):.0f}" if 'rebuilds' in rs[0] else ''
        print(f"| {ds} | {label} | {len(rs)} | {med(rs, 'step_ms_mean'):.3f} | {med(rs, 'step_ms_p50'):.3f} | "
              f"{med(rs, 'step_ms_p99'):.2f} | {med(rs, 'step_ms_max'):.1f} | {chi2:.4f} | {rel} | {rebuilds} | "
              f"{med(rs, 'peak_rss_mb'):.1f} |")
    for label in labels:
        for peer in ('iSAM2', label.replace('new', 'base')):
            if not label.startswith('new') or (ds, peer) not in runs:
                continue
            a, b = runs[(ds, label)], runs[(ds, peer)]
            r = {k: med(a, k) / med(b, k) for k in keys + ['peak_rss_mb']}
            print(f"| {ds} | {label} / {peer} | | **{r['step_ms_mean']:.2f}** | {r['step_ms_p50']:.2f} | "
                  f"**{r['step_ms_p99']:.2f}** | **{r['step_ms_max']:.2f}** | | | | {r['peak_rss_mb']:.2f} |")
