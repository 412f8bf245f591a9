"""sextant.optimize: the same summary and poses as `sextant optimize`, from a file or from records in memory."""
import math

import pytest
import sextant

from conftest import posegraph, tool, tool_json

TIMINGS = {"solve_seconds", "linearize_seconds", "factorize_seconds", "linear_solve_seconds", "step_ms_mean",
           "step_ms_p50", "step_ms_p99", "step_ms_max", "peak_rss_mb", "init_seconds"}


def read_vertices(path):
    """{id: values} of the VERTEX lines of a g2o file (the CLI writes them with 17 digits)."""
    out = {}
    for line in open(path):
        t = line.split()
        if t and t[0].startswith("VERTEX"):
            out[int(t[1])] = [float(x) for x in t[2:]]
    return out


def records(path):
    rows = []
    for line in open(path):
        t = line.split("#")[0].split()
        if t:
            rows.append((t[0], *[int(x) if x.lstrip("-").isdigit() else float(x) for x in t[1:]]))
    return rows


@pytest.mark.parametrize("name,options", [
    ("CSAIL.g2o", {}),
    ("smallGrid3D.g2o", {}),
    ("CSAIL.g2o", {"solver": "lm", "robust": "huber"}),
    ("CSAIL.g2o", {"init": "chordal"}),
])
def test_same_as_the_cli(name, options, tmp_path):
    path = posegraph(name)
    args = []
    for k, v in options.items():
        args += [f"--{k}", v]
    cli_out = tmp_path / "cli.g2o"
    cli = tool_json("optimize", path, "-o", cli_out, *args)
    r = sextant.optimize(path, output=str(tmp_path / "py.g2o"), **options)
    assert r["ok"] and r["message"] == ""
    s = r["summary"]
    assert list(s) == list(cli), "the keys (and their order) of sextant optimize --json"
    for k in cli:
        if k not in TIMINGS:
            assert s[k] == cli[k], k
    assert s["final_chi2"] < s["initial_chi2"]
    assert open(tmp_path / "py.g2o").read() == open(cli_out).read()
    cli_poses = read_vertices(cli_out)
    assert r["poses"].keys() == cli_poses.keys()
    for i, v in cli_poses.items():
        assert r["poses"][i] == v  # 17 significant digits round-trip exactly
    assert set(s) >= {"vertices", "edges", "dimension", "iterations", "initial_chi2", "final_chi2", "solve_seconds",
                      "converged"}


def test_in_memory_graph_equals_the_file():
    path = posegraph("CSAIL.g2o")
    from_file = sextant.optimize(path)
    from_records = sextant.optimize(records(path))
    assert from_records["summary"]["final_chi2"] == from_file["summary"]["final_chi2"]
    assert from_records["poses"] == from_file["poses"]


def test_small_graph_with_known_solution():
    """A square of four planar poses: exact odometry, one loop that disagrees by 0.4 m in x.  With equal
    information on every edge, least squares spreads the loop's 0.4 m error evenly: each of the four x-offsets
    between consecutive poses absorbs 0.1 m, and the final chi2 is 4 * 0.1^2 * 100 = 4 (information 100 in x)."""
    info = (100.0, 0.0, 0.0, 100.0, 0.0, 1000.0)
    graph = [("VERTEX_SE2", i, 0.0, 0.0, 0.0) for i in range(4)] + [
        ("EDGE_SE2", 0, 1, 1.0, 0.0, 0.0, *info),
        ("EDGE_SE2", 1, 2, 1.0, 0.0, 0.0, *info),
        ("EDGE_SE2", 2, 3, 1.0, 0.0, 0.0, *info),
        ("EDGE_SE2", 3, 0, -2.6, 0.0, 0.0, *info),
        ("FIX", 0),
    ]
    r = sextant.optimize(graph)
    assert r["ok"] and r["summary"]["converged"]
    assert r["summary"]["final_chi2"] == pytest.approx(4 * 0.1 ** 2 * 100, rel=1e-9)
    for i in range(4):
        x, y, theta = r["poses"][i]
        assert x == pytest.approx(0.9 * i, abs=1e-9) and abs(y) < 1e-9 and abs(theta) < 1e-9


def test_incremental_same_keys_as_the_cli():
    path = posegraph("CSAIL.g2o")
    cli = tool_json("optimize", path, "--incremental")
    r = sextant.optimize(path, incremental=True)
    assert list(r["summary"]) == list(cli)
    for k in ("vertices", "edges", "updates", "final_chi2", "batch_final_chi2", "rebuilds"):
        assert r["summary"][k] == cli[k], k
    assert r["summary"]["final_chi2_batch_ratio"] == pytest.approx(1.0, abs=1e-3)


def test_errors():
    with pytest.raises(ValueError, match=r"graph\[1\]: EDGE_SE2: expected more values"):
        sextant.optimize([("VERTEX_SE2", 0, 0.0, 0.0, 0.0), ("EDGE_SE2", 0, 1, 1.0)])
    with pytest.raises(ValueError, match=r"graph\[0\]: expected numbers after the tag, got str"):
        sextant.optimize([("VERTEX_SE2", "a", 0.0, 0.0, 0.0)])
    with pytest.raises(ValueError, match=r"unknown solver 'newton' \(gn or lm\)"):
        sextant.optimize(posegraph("CSAIL.g2o"), solver="newton")
    with pytest.raises(ValueError, match="init and solver do not apply"):
        sextant.optimize(posegraph("CSAIL.g2o"), incremental=True, solver="lm")
    with pytest.raises(RuntimeError, match="cannot open"):
        sextant.optimize("/nonexistent.g2o")
    # a graph the optimizer refuses: reported, not raised
    r = sextant.optimize([("VERTEX_SE2", 0, 0.0, 0.0, 0.0), ("VERTEX_SE2", 1, math.nan, 0.0, 0.0),
                          ("EDGE_SE2", 0, 1, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 1.0)])
    assert not r["ok"] and r["message"]
