"""sextant.eval: the numbers of `sextant eval` (TUM benchmark semantics) from files or rows; the version in the
replay JSON."""
import math

import pytest
import sextant

from conftest import tool, tool_json


def rows(path):
    out = []
    for line in open(path):
        if line.strip() and not line.startswith("#"):
            out.append([float(x) for x in line.split()])
    return out


def same(a, b):
    assert list(a) == list(b), "the keys (and their order) of sextant eval --json"
    for k in b:
        if isinstance(b[k], float) or b[k] is None:
            assert (a[k] is None or math.isnan(a[k])) if b[k] is None else a[k] == b[k], k
        else:
            assert a[k] == b[k], k


@pytest.mark.parametrize("options,args", [
    ({}, []),
    ({"scale": True}, ["--scale"]),
    ({"delta": 5, "delta_unit": "f"}, ["--delta", "5", "--delta-unit", "f"]),
])
def test_same_as_the_cli(simulated_run, options, args):
    gt, est = str(simulated_run["gt"]), str(simulated_run["est"])
    cli = tool_json("eval", "--gt", gt, "--est", est, *args)
    same(sextant.eval(gt, est, **options), cli)
    same(sextant.eval(rows(gt), rows(est), **options), cli)
    assert cli["matched"] > 100 and 0 < cli["ate_rmse"] < 5


def test_known_offset():
    """An estimate that is the ground truth shifted by 1 m: ATE 0 after alignment; RPE 0."""
    gt = [[t * 0.1, math.cos(t * 0.1), math.sin(t * 0.1), 0.0, 0.0, 0.0, 0.0, 1.0] for t in range(100)]
    est = [[r[0], r[1] + 1.0, *r[2:]] for r in gt]
    r = sextant.eval(gt, est)
    assert r["matched"] == 100 and r["ate_rmse"] < 1e-9 and r["rpe_trans_rmse"] < 1e-9


def test_kitti_files_same_as_the_cli(tmp_path):
    """KITTI pose files (frame i with frame i): the module and `sextant eval --format kitti` agree, and a 1 % scale
    error over a 300 m run reads as about 1 % in the KITTI error."""
    def kitti(path, scale):
        with open(path, "w") as f:
            for i in range(301):
                f.write(f"1 0 0 {i * scale} 0 1 0 0 0 0 1 0\n")
    gt, est = tmp_path / "gt.txt", tmp_path / "est.txt"
    kitti(gt, 1.0)
    kitti(est, 1.01)
    cli = tool_json("eval", "--gt", str(gt), "--est", str(est), "--format", "kitti")
    same(sextant.eval(str(gt), str(est), format="kitti"), cli)
    assert cli["matched"] == 301 and cli["kitti_segments"] > 0
    assert 1.0 < cli["kitti_trans_pct"] < 1.02 and cli["kitti_rot_deg_per_m"] < 1e-9
    with pytest.raises(ValueError, match="format"):
        sextant.eval(str(gt), str(est), format="csv")


def test_errors(tmp_path):
    with pytest.raises(ValueError, match=r"est\[1\]: expected 8 values, got 3"):
        sextant.eval([[0, 0, 0, 0, 0, 0, 0, 1]] * 2, [[0, 0, 0, 0, 0, 0, 0, 1], [1, 2, 3]])
    with pytest.raises(ValueError, match="fewer than 2|at least 2|2 match"):
        sextant.eval([[0, 0, 0, 0, 0, 0, 0, 1]], [[5, 0, 0, 0, 0, 0, 0, 1]])
    with pytest.raises(ValueError, match="delta_unit"):
        sextant.eval([], [], delta_unit="m")


def test_version_everywhere(simulated_run):
    v = tool("--version").strip()
    assert v and sextant.__version__ == v
    assert simulated_run["replay_json"]["version"] == v
