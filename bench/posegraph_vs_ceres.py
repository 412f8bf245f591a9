#!/usr/bin/env python3
"""sextant optimize against Ceres 2.1 on the shared pose graphs, interleaved, median of N runs.

Usage: bench/posegraph_vs_ceres.py BUILD_DIR CERES_BIN [--reps N] [--out FILE] [--datasets a,b,...] [--process]
Each repetition runs, for every data set in turn: Ceres (LM, SPARSE_NORMAL_CHOLESKY on SuiteSparse, 1 thread, the
harness in ../shared/peers/ceres_posegraph, gauge = highest id as in the peer table), then sextant GN and LM from
the file's initial guess (and, for torus3D, GN from the chordal initialization).  Solve time = the optimizer's own
time (Ceres: Summary::total_time_in_seconds; sextant: JSON solve_seconds = initialization + optimization), not
file reading.  Medians over the repetitions; the ratio is sextant / Ceres measured in the same run.

--process times each whole process instead (wall clock from fork to exit: start-up, reading, solving, output), the
default `sextant optimize D.g2o --json` (GN, --init auto) against the Ceres harness, alternating which goes first.
That is what a user of a small problem waits for.  The KITTI sets have no vertices: both programs then read the same
copy with the odometry chain written as vertices (the Ceres harness needs them; sextant would compose the same chain).
"""
import datetime
import json
import math
import os
import platform
import re
import statistics
import subprocess
import sys
import tempfile
import time

DATASETS = [("intel", 1727), ("M3500", 3499), ("city10000", 9999), ("sphere2500", 2499), ("torus3D", 4999),
            ("parking-garage", 1660), ("kitti_00", 4540), ("kitti_02", 4660)]
PROCESS_DEFAULT = ["intel", "kitti_00", "kitti_02", "M3500", "city10000", "sphere2500"]


def run(cmd):
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    return out


def ceres(bin_, path, fix):
    out = run([bin_, "-fix", str(fix), path])
    kv = dict(re.findall(r"(\w+)=(\S+)", out))
    return {"solve": float(kv["ceres_total_s"]), "chi2": float(kv["final_chi2"]), "iters": int(kv["iterations"])}


def sextant(build, path, solver, init):
    out = json.loads(run([f"{build}/bin/sextant", "optimize", path, "--json", "--solver", solver, "--init", init]))
    return {"solve": out["solve_seconds"], "chi2": out["final_chi2"], "iters": out["iterations"]}


def with_odometry_vertices(path, tmpdir):
    """PATH itself if it has vertices; else a copy in TMPDIR with VERTEX_SE2 lines composed along the i -> i+1 edges
    (x_j = x_i (+) z_ij, planar), which is the start both the Ceres harness and `--init file` then read."""
    lines = open(path).read().splitlines()
    if any(l.startswith("VERTEX") for l in lines):
        return path
    pose = {0: (0.0, 0.0, 0.0)}
    for l in lines:
        f = l.split()
        if f and f[0] == "EDGE_SE2" and int(f[2]) == int(f[1]) + 1 and int(f[1]) in pose:
            x, y, t = pose[int(f[1])]
            dx, dy, dt = map(float, f[3:6])
            pose[int(f[2])] = (x + math.cos(t) * dx - math.sin(t) * dy, y + math.sin(t) * dx + math.cos(t) * dy,
                               math.atan2(math.sin(t + dt), math.cos(t + dt)))
    out = os.path.join(tmpdir, os.path.basename(path))
    with open(out, "w") as f:
        f.writelines(f"VERTEX_SE2 {i} {x:.17g} {y:.17g} {t:.17g}\n" for i, (x, y, t) in sorted(pose.items()))
        f.write("\n".join(lines) + "\n")
    return out


def write_table(lines, out_path):
    """Prints the table's lines and writes them to OUT_PATH when given."""
    text = "\n".join(lines) + "\n"
    print(text)
    if out_path:
        with open(out_path, "w") as f:
            f.write(text)


def timed(cmd):
    """Wall seconds of the whole process CMD and its standard output."""
    t0 = time.perf_counter()
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    return time.perf_counter() - t0, out


def process_main(build, ceres_bin, reps, out_path, names):
    sets = [(n, f) for n, f in DATASETS if n in (names or PROCESS_DEFAULT)]
    data = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "data", "posegraph")
    tmp = tempfile.TemporaryDirectory()
    paths = {n: with_odometry_vertices(os.path.join(data, n + ".g2o"), tmp.name) for n, _ in sets}
    runs = {}
    for rep in range(reps):
        for name, fix in sets:
            def run_ceres():
                wall, out = timed([ceres_bin, "-fix", str(fix), paths[name]])
                return {"wall": wall, "chi2": float(dict(re.findall(r"(\w+)=(\S+)", out))["final_chi2"])}

            def run_sextant():
                wall, out = timed([f"{build}/bin/sextant", "optimize", paths[name], "--json"])
                j = json.loads(out)
                return {"wall": wall, "chi2": j["final_chi2"], "iters": j["iterations"], "init": j["init_used"]}

            order = [("Ceres", run_ceres), ("sextant", run_sextant)]
            for label, fn in order if rep % 2 == 0 else order[::-1]:
                runs.setdefault((name, label), []).append(fn())
            c, s = runs[(name, "Ceres")][-1], runs[(name, "sextant")][-1]
            print(f"rep {rep + 1} {name:12s} sextant {s['wall']:.3f} s  Ceres {c['wall']:.3f} s  "
                  f"ratio {s['wall'] / c['wall']:.2f}", flush=True)
    lines = [f"Measured {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC on {platform.node()} "
             f"({os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}), whole processes, median of {reps} interleaved "
             f"rounds: `bench/posegraph_vs_ceres.py {build} {ceres_bin} --process --reps {reps}`.", "",
             "| data set | sextant chi2 | iterations (init) | sextant wall s | Ceres chi2 | Ceres wall s | "
             "ratio of medians | median of per-round ratios |", "|---|---|---|---|---|---|---|---|"]
    for name, _ in sets:
        s, c = runs[(name, "sextant")], runs[(name, "Ceres")]
        ms, mc = statistics.median(r["wall"] for r in s), statistics.median(r["wall"] for r in c)
        per_round = statistics.median(a["wall"] / b["wall"] for a, b in zip(s, c))
        lines.append(f"| {name} | {s[0]['chi2']:.6f} | {s[0]['iters']} ({s[0]['init']}) | {ms:.3f} | "
                     f"{c[0]['chi2']:.6f} | {mc:.3f} | {ms / mc:.2f} | {per_round:.2f} |")
    write_table(lines, out_path)


def main():
    build, ceres_bin = sys.argv[1], sys.argv[2]
    reps = int(sys.argv[sys.argv.index("--reps") + 1]) if "--reps" in sys.argv else 3
    out_path = sys.argv[sys.argv.index("--out") + 1] if "--out" in sys.argv else None
    names = sys.argv[sys.argv.index("--datasets") + 1].split(",") if "--datasets" in sys.argv else None
    if "--process" in sys.argv:
        return process_main(build, ceres_bin, reps, out_path, names)
    data = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "data", "posegraph")
    sets = [(n, f) for n, f in DATASETS if names is None or n in names]
    tmp = tempfile.TemporaryDirectory()
    runs = {}
    for rep in range(reps):
        for name, fix in sets:
            path = with_odometry_vertices(os.path.join(data, name + ".g2o"), tmp.name)
            configs = [("Ceres LM", lambda: ceres(ceres_bin, path, fix)),
                       ("sextant GN", lambda: sextant(build, path, "gn", "file")),
                       ("sextant LM", lambda: sextant(build, path, "lm", "file"))]
            if name == "torus3D":
                configs.append(("sextant GN, chordal init", lambda: sextant(build, path, "gn", "chordal")))
            for label, fn in configs:
                r = fn()
                runs.setdefault((name, label), []).append(r)
                print(f"rep {rep + 1} {name:15s} {label:26s} solve {r['solve']:8.3f} s  chi2 {r['chi2']:.6f}  "
                      f"iters {r['iters']}", flush=True)
    lines = [f"Measured {datetime.date.today()} on {platform.node()} ({os.cpu_count()} cores), median of {reps} "
             f"interleaved runs: `bench/posegraph_vs_ceres.py {build} {ceres_bin} --reps {reps}`.", "",
             "| data set | solver | iterations | final chi2 | median solve s | ratio to Ceres (same run) |",
             "|---|---|---|---|---|---|"]
    for name, _ in sets:
        base = statistics.median(r["solve"] for r in runs[(name, "Ceres LM")])
        for (n, label), rs in runs.items():
            if n != name:
                continue
            med = statistics.median(r["solve"] for r in rs)
            lines.append(f"| {name} | {label} | {rs[0]['iters']} | {rs[0]['chi2']:.6f} | {med:.3f} | "
                         f"{med / base:.2f} |")
    write_table(lines, out_path)


if __name__ == "__main__":
    main()
