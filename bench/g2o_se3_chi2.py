#!/usr/bin/env python3
# chi2 of a 3-D g2o pose graph (EDGE_SE3:QUAT) under three definitions of the edge error, computed independently
# of sextant (pure Python quaternions): g2o's EdgeSE3 error [t, q.xyz] of Z^-1 Xi^-1 Xj (q with w >= 0, g2o's
# internal::toVectorMQT), Ceres' pose_graph_3d error [t, 2 q.xyz], and [t, rotation angle x axis] (the SO(3) log).
# Used to check whether a peer's chi2 is the same function as sextant's (bench/RESULTS.md, parking-garage).
# Usage: bench/g2o_se3_chi2.py GRAPH.g2o [--raw-measurements]   (--raw: measurement quaternions as printed)
import math, sys
def qmul(a, b):
    ax, ay, az, aw = a; bx, by, bz, bw = b
    return (aw*bx + ax*bw + ay*bz - az*by, aw*by - ax*bz + ay*bw + az*bx, aw*bz + ax*by - ay*bx + az*bw, aw*bw - ax*bx - ay*by - az*bz)
def qconj(q): return (-q[0], -q[1], -q[2], q[3])
def qnorm(q):
    n = math.sqrt(sum(c*c for c in q)); return tuple(c/n for c in q)
def qrot(q, v):
    r = qmul(qmul(q, (v[0], v[1], v[2], 0.0)), qconj(q)); return r[:3]
def inv(p):
    t, q = p; qi = qconj(q); ti = qrot(qi, t); return ((-ti[0], -ti[1], -ti[2]), qi)
def mul(a, b):
    ta, qa = a; tb, qb = b; r = qrot(qa, tb); return ((ta[0]+r[0], ta[1]+r[1], ta[2]+r[2]), qnorm(qmul(qa, qb)))
def read(path, normalize_meas=True):
    V, E = {}, []
    for line in open(path):
        f = line.split()
        if not f: continue
        if f[0] == 'VERTEX_SE3:QUAT':
            x = list(map(float, f[2:9])); V[int(f[1])] = (tuple(x[:3]), qnorm(tuple(x[3:7])))
        elif f[0] == 'EDGE_SE3:QUAT':
            x = list(map(float, f[3:10])); q = tuple(x[3:7])
            up = list(map(float, f[10:31])); O = [[0.0]*6 for _ in range(6)]; k = 0
            for i in range(6):
                for j in range(i, 6): O[i][j] = O[j][i] = up[k]; k += 1
            E.append((int(f[1]), int(f[2]), (tuple(x[:3]), qnorm(q) if normalize_meas else q), O))
    return V, E
def err(kind, D):
    t, q = D
    if q[3] < 0: q = tuple(-c for c in q)
    if kind == 'g2o':  # g2o EdgeSE3: toVectorMQT = [t, q.xyz] with w >= 0
        return list(t) + list(q[:3])
    if kind == 'ceres':  # Ceres pose_graph_3d: [t, 2 q.xyz]
        return list(t) + [2*c for c in q[:3]]
    if kind == 'log_rot':  # [t, axis*angle] (the SO(3) log; translation kept)
        s = math.sqrt(sum(c*c for c in q[:3])); ang = 2*math.atan2(s, q[3])
        k = ang/s if s > 1e-15 else 2.0
        return list(t) + [k*c for c in q[:3]]
def chi2(V, E, kind):
    total = 0.0
    for i, j, z, O in E:
        D = mul(inv(z), mul(inv(V[i]), V[j]))
        e = err(kind, D)
        total += sum(e[a]*O[a][b]*e[b] for a in range(6) for b in range(6))
    return total
V, E = read(sys.argv[1], normalize_meas="--raw-measurements" not in sys.argv)
for kind in ('g2o', 'ceres', 'log_rot'):
    print(kind, '%.8f' % chi2(V, E, kind))
