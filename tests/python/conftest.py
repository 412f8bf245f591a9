"""Shared by the Python module's tests: where the tools and data are (set by ctest, see tests/CMakeLists.txt) and
helpers that run the `sextant` tool, whose outputs the module must reproduce."""
import json
import os
import subprocess

import pytest

BIN = os.environ.get("SEXTANT_BIN", "")
SOURCE = os.environ.get("SEXTANT_SOURCE_DIR", "")
SHARED = os.environ.get("SEXTANT_SHARED_DIR", "")
LCMTYPES_PY = os.environ.get("SEXTANT_LCMTYPES_PY", "")


def tool(*args, check=True):
    """Runs build/bin/sextant with args; returns its stdout."""
    r = subprocess.run([os.path.join(BIN, "sextant"), *map(str, args)], capture_output=True, text=True)
    if check and r.returncode != 0:
        raise AssertionError(f"sextant {' '.join(map(str, args))}: exit {r.returncode}\n{r.stderr}")
    return r.stdout


def tool_json(*args):
    return json.loads(tool(*args, "--json"))


def posegraph(name):
    path = os.path.join(SHARED, "data", "posegraph", name)
    if not os.path.exists(path):
        raise AssertionError(f"shared data set missing: {path}")
    return path


@pytest.fixture(scope="module")
def simulated_run(tmp_path_factory):
    """A 30 s simulated planar run (log and ground truth) and its deterministic replay (TUM estimate, output log)."""
    d = tmp_path_factory.mktemp("sim")
    log = d / "run.lcm"
    tool("simulate", "planar", "-o", log, "--seed", 2, "--duration", 30)
    est = d / "est.txt"
    out = d / "replayed.lcm"
    config = os.path.join(SOURCE, "config", "default.yaml")
    replay = json.loads(tool("replay", log, "--config", config, "--tum-out", est, "--out-log", out, "--json"))
    return {"log": log, "gt": d / "run_gt.txt", "est": est, "replayed": out, "replay_json": replay, "dir": d}
