"""The TUM loop-closure experiment, offline check of the daemon's keyframe graph.

From the converted log (vo.lcm: ODOMETRY with increment covariances, GROUND_TRUTH) and an lcm-logger recording of
the daemon's run (bus.lcm: the final TRAJECTORY's keyframes and the matcher's LOOP_CLOSURES), rebuilds the keyframe
graph independently of the daemon's code: odometry edges O_i^-1 O_j between consecutive keyframes with the
covariance composed from the increments (Sigma <- Ad(delta^-1) Sigma Ad(delta^-1)' + Q, right perturbation, as
daemon/engine/pose_covariance.hpp), and the answered loops.  It then
  - scores the covariances against the truth: mean chi2 of the odometry edges' and the loops' errors w.r.t. the
    ground truth under their stated covariance (an honest 6-D covariance gives 6), and the loops' true/wrong split;
  - writes g2o graphs of variants and optimizes them with `sextant optimize`, ATE (`sextant eval`) at the keyframe
    times: all loops or only the true ones, robust kernel none or DCS, and the information either as the daemon
    passes it (tangent-space, rotation in radians) or converted to the residual of EDGE_SE3:QUAT, whose rotation
    part is vec(q) ~ theta / 2 (Omega_g2o = T Omega T, T = diag(I, 2 I)).
Usage: tum_graph_diagnosis.py VO.lcm BUS.lcm GT.txt BUILD_BIN PYTHON_TYPES TESTS_E2E WORKDIR
Prints the raw odometry's drift at its full rate (ATE, RPE over 1 s), then one line per variant: name, loops used,
ATE [m].  With BUS.lcm "-" only the odometry's drift.
"""
import json
import math
import os
import subprocess
import sys

sys.path.insert(0, sys.argv[5])
sys.path.insert(0, sys.argv[6])
from lcmlog import read_log, TrajectoryRebuild  # noqa: E402
from sextant import loop_closure_t, odometry_t, trajectory_t, truth_t  # noqa: E402


# --- SE(3) in pure Python: a pose is (R as 3x3 nested lists, t as a list of 3) ---------------------------------
def qmat(w, x, y, z):
    n = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def mat_quat(R):  # -> (w, x, y, z)
    tr = R[0][0] + R[1][1] + R[2][2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        return (0.25 * s, (R[2][1] - R[1][2]) / s, (R[0][2] - R[2][0]) / s, (R[1][0] - R[0][1]) / s)
    if R[0][0] > R[1][1] and R[0][0] > R[2][2]:
        s = math.sqrt(1.0 + R[0][0] - R[1][1] - R[2][2]) * 2
        return ((R[2][1] - R[1][2]) / s, 0.25 * s, (R[0][1] + R[1][0]) / s, (R[0][2] + R[2][0]) / s)
    if R[1][1] > R[2][2]:
        s = math.sqrt(1.0 + R[1][1] - R[0][0] - R[2][2]) * 2
        return ((R[0][2] - R[2][0]) / s, (R[0][1] + R[1][0]) / s, 0.25 * s, (R[1][2] + R[2][1]) / s)
    s = math.sqrt(1.0 + R[2][2] - R[0][0] - R[1][1]) * 2
    return ((R[1][0] - R[0][1]) / s, (R[0][2] + R[2][0]) / s, (R[1][2] + R[2][1]) / s, 0.25 * s)


def mm(A, B):
    return [[sum(A[i][k] * B[k][j] for k in range(len(B))) for j in range(len(B[0]))] for i in range(len(A))]


def tr(A):
    return [list(r) for r in zip(*A)]


def mv(A, v):
    return [sum(A[i][k] * v[k] for k in range(len(v))) for i in range(len(A))]


def compose(a, b):
    return (mm(a[0], b[0]), [x + y for x, y in zip(mv(a[0], b[1]), a[1])])


def inverse(a):
    Rt = tr(a[0])
    return (Rt, [-x for x in mv(Rt, a[1])])


def between(a, b):
    return compose(inverse(a), b)


def hat(v):
    return [[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]]


def so3_log(R):
    c = max(-1.0, min(1.0, (R[0][0] + R[1][1] + R[2][2] - 1) / 2))
    th = math.acos(c)
    v = [R[2][1] - R[1][2], R[0][2] - R[2][0], R[1][0] - R[0][1]]
    k = 0.5 if th < 1e-9 else th / (2 * math.sin(th))
    return [k * x for x in v]


def error_vector(e):
    """sextant's tangent error [t; log R] of a small pose error (V ~ I)."""
    return e[1] + so3_log(e[0])


def adjoint(a):
    """Ad(T) for xi = [translation; rotation]: [[R, [t]x R], [0, R]]."""
    R, t = a
    tR = mm(hat(t), R)
    top = [R[i] + tR[i] for i in range(3)]
    bottom = [[0.0] * 3 + R[i] for i in range(3)]
    return top + bottom


def add(A, B):
    return [[a + b for a, b in zip(ra, rb)] for ra, rb in zip(A, B)]


def inv6(A):
    n = len(A)
    M = [list(A[i]) + [1.0 if i == j else 0.0 for j in range(n)] for i in range(n)]
    for c in range(n):
        p = max(range(c, n), key=lambda r: abs(M[r][c]))
        M[c], M[p] = M[p], M[c]
        d = M[c][c]
        M[c] = [x / d for x in M[c]]
        for r in range(n):
            if r != c and M[r][c] != 0:
                f = M[r][c]
                M[r] = [x - f * y for x, y in zip(M[r], M[c])]
    return [row[n:] for row in M]


def quad(v, A):
    return sum(v[i] * A[i][j] * v[j] for i in range(len(v)) for j in range(len(v)))


def g2o_information(info, convert):
    if not convert:
        return info
    s = [1, 1, 1, 2, 2, 2]
    return [[info[i][j] * s[i] * s[j] for j in range(6)] for i in range(6)]


def pose_of(m):
    return (qmat(*m.orientation), list(m.position))


def main():
    vo, bus, gt_path, bindir, _, _, work = sys.argv[1:8]
    os.makedirs(work, exist_ok=True)
    odom, inc, truth = {}, {}, {}
    for _, c, b in read_log(vo):
        if c == "ODOMETRY":
            m = odometry_t.decode(b)
            odom[m.utime] = pose_of(m)
            inc[m.utime] = [list(m.increment_covariance[6 * i:6 * i + 6]) for i in range(6)]
        elif c == "GROUND_TRUTH":
            m = truth_t.decode(b)
            truth[m.utime] = pose_of(m)
    def evaluate(path):
        out = subprocess.run([os.path.join(bindir, "sextant"), "eval", "--gt", gt_path, "--est", path, "--json"],
                             check=True, capture_output=True, text=True).stdout
        return json.loads(out)

    def write_tum(path, items):
        with open(path, "w") as f:
            for u, p in items:
                w, x, y, z = mat_quat(p[0])
                f.write(f"{u * 1e-6:.6f} {p[1][0]:.9f} {p[1][1]:.9f} {p[1][2]:.9f} {x:.9f} {y:.9f} {z:.9f} {w:.9f}\n")

    write_tum(os.path.join(work, "odometry_full.txt"), sorted(odom.items()))
    j = evaluate(os.path.join(work, "odometry_full.txt"))
    print(f"odometry at its full rate: ATE {j['ate_rmse']:.4f} m, RPE over 1 s {j['rpe_trans_rmse']:.4f} m "
          f"{j['rpe_rot_rmse_deg']:.2f} deg")
    if bus == "-":
        return
    rebuild, source, loops = TrajectoryRebuild(), None, []
    for _, c, b in read_log(bus):
        if c == "TRAJECTORY":
            m = trajectory_t.decode(b)
            rebuild.add(m)
            source = m.source
        elif c == "LOOP_CLOSURES":
            loops.append(loop_closure_t.decode(b))
    final_keyframes = rebuild.keyframes(source)
    kf = [k.utime for k in final_keyframes]
    index = {u: i for i, u in enumerate(kf)}
    stamps = sorted(odom)

    # Odometry edges between consecutive keyframes and their composed covariance.
    edges = []
    pos = stamps.index(kf[0])
    for i in range(1, len(kf)):
        S = [[0.0] * 6 for _ in range(6)]
        while stamps[pos] < kf[i]:
            a, b = stamps[pos], stamps[pos + 1]
            ad = adjoint(inverse(between(odom[a], odom[b])))
            S = add(mm(mm(ad, S), tr(ad)), inc[b])
            for d in range(6):
                S[d][d] += 1e-10  # the graph stage's min_increment_variance
            pos += 1
        z = between(odom[kf[i - 1]], odom[kf[i]])
        edges.append((i - 1, i, z, inv6(S), True))
    odo_chi2 = [quad(error_vector(between(z, between(truth[kf[a]], truth[kf[b]]))), info) for a, b, z, info, _ in edges]

    # Loops: those between keyframes of the final trajectory, true or wrong against the ground truth.
    loop_edges, loop_chi2 = [], []
    for m in loops:
        if m.utime_from not in index or m.utime_to not in index:
            continue
        z = pose_of(m)
        info = [list(m.information[6 * i:6 * i + 6]) for i in range(6)]
        e = error_vector(between(z, between(truth[m.utime_from], truth[m.utime_to])))
        wrong = math.sqrt(sum(x * x for x in e[:3])) > 0.2 or math.sqrt(sum(x * x for x in e[3:])) > 0.1
        if not wrong:
            loop_chi2.append(quad(e, info))
        loop_edges.append((index[m.utime_from], index[m.utime_to], z, info, not wrong))
    mean = lambda x: sum(x) / len(x) if x else float("nan")  # noqa: E731
    print(f"keyframes {len(kf)}  odometry edges {len(edges)}: mean chi2 vs truth {mean(odo_chi2):.1f} (6 if honest)")
    print(f"loops {len(loop_edges)} ({sum(1 for e in loop_edges if not e[4])} wrong): mean chi2 of true loops vs truth "
          f"{mean(loop_chi2):.2f} (6 if honest)")

    def ate(name, poses):
        path = os.path.join(work, name + ".txt")
        write_tum(path, zip(kf, poses))
        return evaluate(path)["ate_rmse"]

    print(f"{'variant':58s} loops  ATE [m]")
    print(f"{'odometry at the keyframes':58s} {0:5d}  {ate('odometry', [odom[u] for u in kf]):.4f}")
    print(f"{'daemon: final TRAJECTORY':58s} {'-':>5s}  {ate('daemon', [pose_of(k) for k in final_keyframes]):.4f}")
    for true_only in (False, True):
        for convert in (False, True):
            for robust in ("dcs", "none"):
                if robust == "none" and not true_only:
                    continue
                used = [e for e in loop_edges if e[4] or not true_only]
                g = os.path.join(work, "graph.g2o")
                with open(g, "w") as f:
                    for i, u in enumerate(kf):
                        w, x, y, z = mat_quat(odom[u][0])
                        t = odom[u][1]
                        f.write(f"VERTEX_SE3:QUAT {i} {t[0]:.12g} {t[1]:.12g} {t[2]:.12g} {x:.12g} {y:.12g} {z:.12g} {w:.12g}\n")
                    f.write("FIX 0\n")
                    for a, b, z, info, _ in edges + used:
                        I = g2o_information(info, convert)
                        w, x, y, q = mat_quat(z[0])
                        up = " ".join(f"{I[r][c]:.12g}" for r in range(6) for c in range(r, 6))
                        f.write(f"EDGE_SE3:QUAT {a} {b} {z[1][0]:.12g} {z[1][1]:.12g} {z[1][2]:.12g} "
                                f"{x:.12g} {y:.12g} {q:.12g} {w:.12g} {up}\n")
                o = os.path.join(work, "out.g2o")
                subprocess.run([os.path.join(bindir, "sextant"), "optimize", g, "-o", o, "--robust", robust,
                                "--max-iters", "50"], check=True, capture_output=True)
                poses = {}
                for line in open(o):
                    t = line.split()
                    if t and t[0] == "VERTEX_SE3:QUAT":
                        v = [float(x) for x in t[2:]]
                        poses[int(t[1])] = (qmat(v[6], v[3], v[4], v[5]), v[:3])
                name = (f"{'true loops' if true_only else 'all loops'}, "
                        f"{'information converted to g2o residual' if convert else 'tangent information (as daemon)'}, {robust}")
                print(f"{name:58s} {len(used):5d}  {ate('v', [poses[i] for i in range(len(kf))]):.4f}")


if __name__ == "__main__":
    main()
