#!/usr/bin/env python3
"""sextant optimize against Ceres 2.1 on the shared pose graphs, interleaved, median of N runs.

Usage: bench/posegraph_vs_ceres.py BUILD_DIR CERES_BIN [--reps N] [--out FILE] [--datasets a,b,...]
Each repetition runs, for every data set in turn: Ceres (LM, SPARSE_NORMAL_CHOLESKY on SuiteSparse, 1 thread, the
harness in ../shared/peers/ceres_posegraph, gauge = highest id as in the peer table), then sextant GN and LM from
the file's initial guess (and, for torus3D, GN from the chordal initialization).  Solve time = the optimizer's own
time (Ceres: Summary::total_time_in_seconds; sextant: JSON solve_seconds = initialization + optimization), not
file reading.  Medians over the repetitions; the ratio is sextant / Ceres measured in the same run.
"""
import datetime
import json
import os
import platform
import re
import statistics
import subprocess
import sys

DATASETS = [("intel", 1727), ("M3500", 3499), ("city10000", 9999), ("sphere2500", 2499), ("torus3D", 4999),
            ("parking-garage", 1660)]


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


def main():
    build, ceres_bin = sys.argv[1], sys.argv[2]
    reps = int(sys.argv[sys.argv.index("--reps") + 1]) if "--reps" in sys.argv else 3
    out_path = sys.argv[sys.argv.index("--out") + 1] if "--out" in sys.argv else None
    names = sys.argv[sys.argv.index("--datasets") + 1].split(",") if "--datasets" in sys.argv else None
    data = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "data", "posegraph")
    sets = [(n, f) for n, f in DATASETS if names is None or n in names]
    runs = {}
    for rep in range(reps):
        for name, fix in sets:
            path = os.path.join(data, name + ".g2o")
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
    text = "\n".join(lines) + "\n"
    print(text)
    if out_path:
        with open(out_path, "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
