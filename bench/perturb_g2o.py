#!/usr/bin/env python3
"""Perturbs every VERTEX_SE3:QUAT of a g2o file: translation + N(0, SIGMA_T) per axis, rotation composed with exp of
a rotation vector drawn N(0, SIGMA_R) per axis.  Used to test whether an optimum is a basin others can escape.

Usage: bench/perturb_g2o.py IN.g2o OUT.g2o SEED SIGMA_T SIGMA_R"""
import sys, random, math
src, dst, seed, st, sr = sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5])
rng = random.Random(seed)
def qmul(a, b):
    aw, ax, ay, az = a; bw, bx, by, bz = b
    return (aw*bw-ax*bx-ay*by-az*bz, aw*bx+ax*bw+ay*bz-az*by, aw*by-ax*bz+ay*bw+az*bx, aw*bz+ax*by-ay*bx+az*bw)
out = []
for line in open(src):
    f = line.split()
    if f and f[0] == 'VERTEX_SE3:QUAT':
        i = f[1]; x, y, z, qx, qy, qz, qw = map(float, f[2:9])
        x += rng.gauss(0, st); y += rng.gauss(0, st); z += rng.gauss(0, st)
        v = [rng.gauss(0, sr) for _ in range(3)]; a = math.sqrt(sum(c*c for c in v))
        dq = (math.cos(a/2),) + tuple((c/a)*math.sin(a/2) if a > 0 else 0 for c in v)
        w, qx, qy, qz = qmul((qw, qx, qy, qz), dq)
        line = f"VERTEX_SE3:QUAT {i} {x:.17g} {y:.17g} {z:.17g} {qx:.17g} {qy:.17g} {qz:.17g} {w:.17g}\n"
    out.append(line)
open(dst, 'w').writelines(out)
