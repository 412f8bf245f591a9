#!/usr/bin/env python3
"""robot_localization's bag 1 with GNSS: each estimate (TUM files, ENU at the first fix) against the fixes.

  bag1_gnss_eval.py LOG GAP_START GAP_END NAME=TUM [NAME=TUM ...]

Prints per estimate the horizontal RMS against the fixes outside the gap (at each fix's time, the pose nearest in
time), the same from 30 s on (once an estimator that finds its heading from the first fixes has it: before, its
track runs on the start's heading), and the horizontal distance at the gap's end between the estimate and the first fix after it (the drift
accumulated without GNSS).  The fixes are turned into East-North-Up at the first fix with WGS-84 (ECEF, then the
tangent plane, tests/e2e/wgs84.py): the daemon's datum when none is configured.
"""
import bisect
import math
import sys

import lcmlog
from wgs84 import enu
from sextant import gnss_t

HEADING_KNOWN_S = 30.0


def read_tum(path):
    rows = [l.split() for l in open(path) if l.strip() and not l.startswith("#")]
    return [float(r[0]) for r in rows], [(float(r[1]), float(r[2]), float(r[3])) for r in rows]


def nearest(times, t):
    i = bisect.bisect_left(times, t)
    return min((j for j in (i - 1, i) if 0 <= j < len(times)), key=lambda j: abs(times[j] - t))


def main():
    log, gap_start, gap_end = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
    fixes = lcmlog.decode_all(log, "GNSS", gnss_t)
    origin = (fixes[0].latitude, fixes[0].longitude, fixes[0].altitude)
    t0 = fixes[0].utime * 1e-6
    points = [(f.utime * 1e-6, enu(origin, f.latitude, f.longitude, f.altitude)) for f in fixes]
    after_gap = next(p for p in points if p[0] - t0 >= gap_end)
    for spec in sys.argv[4:]:
        name, path = spec.split("=", 1)
        times, poses = read_tum(path)
        sq, n, sq_late, n_late = 0.0, 0, 0.0, 0
        for t, z in points:
            if gap_start <= t - t0 < gap_end:
                continue
            p = poses[nearest(times, t)]
            e2 = (p[0] - z[0]) ** 2 + (p[1] - z[1]) ** 2
            sq, n = sq + e2, n + 1
            if t - t0 >= HEADING_KNOWN_S:
                sq_late, n_late = sq_late + e2, n_late + 1
        p = poses[nearest(times, after_gap[0])]
        drift = math.hypot(p[0] - after_gap[1][0], p[1] - after_gap[1][1])
        print(f"{name}: horizontal RMS against {n} fixes {math.sqrt(sq / n):.3f} m ({math.sqrt(sq_late / n_late):.3f} m "
              f"from {HEADING_KNOWN_S:.0f} s); at the gap's end ({after_gap[0] - t0:.1f} s) {drift:.3f} m from the fix")


if __name__ == "__main__":
    main()
