#!/usr/bin/env python3
"""The initialization's time of two `sextant` binaries on the shared pose graphs, interleaved, medians.

Usage: bench/init_ab.py OLD_SEXTANT NEW_SEXTANT intel,kitti_00,... REPS
Runs `sextant optimize D.g2o --json` (the default: GN, --init auto) REPS times per binary, alternating which goes
first, and prints per set the medians of `init_seconds`, their ratio (new / old), each binary's final chi2 and the
initialization it used.  A check that a change to the initialization keeps its answer and what it saves.
"""
import json
import os
import statistics
import subprocess
import sys

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'shared', 'data', 'posegraph')


def run(binary, path):
    out = subprocess.run([binary, 'optimize', path, '--json'], capture_output=True, text=True, check=True).stdout
    return json.loads(out[out.index('{'):])


def main():
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    old, new, sets, reps = sys.argv[1], sys.argv[2], sys.argv[3].split(','), int(sys.argv[4])
    for name in sets:
        path = os.path.join(DATA, name + '.g2o')
        times, last = {'old': [], 'new': []}, {}
        for k in range(reps):
            order = [('old', old), ('new', new)] if k % 2 == 0 else [('new', new), ('old', old)]
            for label, binary in order:
                j = run(binary, path)
                times[label].append(j['init_seconds'])
                last[label] = j
        mo, mn = statistics.median(times['old']), statistics.median(times['new'])
        print(f"{name}: init ms old {mo * 1e3:.2f} new {mn * 1e3:.2f} ratio {mn / mo:.3f}; final chi2 old "
              f"{last['old']['final_chi2']:.10g} new {last['new']['final_chi2']:.10g}; init used "
              f"{last['old']['init_used']} / {last['new']['init_used']}")


if __name__ == '__main__':
    main()
