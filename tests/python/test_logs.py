"""LCM logs: read what `sextant simulate` and replay write, write logs the tools read back; checked against an
independent reader of lcm-logger's format (tests/e2e/lcmlog.py)."""
import os
import struct
import sys
import warnings

import pytest
import sextant

from conftest import SOURCE, tool

sys.path.insert(0, os.path.join(SOURCE, "tests", "e2e"))
import lcmlog  # noqa: E402  (the end-to-end tests' pure-Python reader)


def test_read_log_matches_an_independent_reader(simulated_run):
    events = sextant.read_log(str(simulated_run["log"]))
    assert len(events) > 100
    assert events == list(lcmlog.read_log(str(simulated_run["log"])))
    assert list(sextant.LogReader(str(simulated_run["log"]))) == events


def test_every_simulated_message_decodes(simulated_run):
    channels = {}
    for ts, channel, data in sextant.read_log(str(simulated_run["replayed"])) + sextant.read_log(str(simulated_run["log"])):
        msg = sextant.decode(data)
        channels.setdefault(channel, set()).add(sextant.message_type(data))
        if "utime" in msg:
            assert msg["utime"] > 0
    assert channels["ODOMETRY"] == {"odometry_t"}
    assert channels["FUSED_POSE"] == {"fused_pose_t"}
    assert channels["GROUND_TRUTH"] == {"truth_t"}
    # the replay's odometry and fused poses pair up one to one
    odo = [sextant.decode(d) for _, c, d in sextant.read_log(str(simulated_run["log"])) if c == "ODOMETRY"]
    fused = [sextant.decode(d) for _, c, d in sextant.read_log(str(simulated_run["replayed"])) if c == "FUSED_POSE"]
    assert [m["utime"] for m in fused] == [m["utime"] for m in odo]


def test_written_log_replays_like_the_original(simulated_run, tmp_path):
    """A log re-written through the module, message by message from dicts, is byte-identical and replays to the
    same JSON as the original."""
    copy = tmp_path / "copy.lcm"
    with sextant.LogWriter(str(copy)) as w:
        for ts, channel, data in sextant.read_log(str(simulated_run["log"])):
            w.write_message(ts, channel, sextant.message_type(data), sextant.decode(data))
        n = w.events_written
    assert n == len(sextant.read_log(str(simulated_run["log"]))) == w.events_written  # also after closing
    assert open(copy, "rb").read() == open(simulated_run["log"], "rb").read()


def test_writer_errors(tmp_path):
    with pytest.raises(RuntimeError, match="nope"):
        sextant.LogWriter(str(tmp_path / "nope" / "x.lcm"))
    w = sextant.LogWriter(str(tmp_path / "x.lcm"))
    with pytest.raises(ValueError, match="odometry_t: unknown field"):
        w.write_message(1, "ODOMETRY", "odometry_t", {"bogus": 1})
    w.close()
    with pytest.raises(ValueError, match="closed"):
        w.write(1, "X", b"abc")
    with pytest.raises(RuntimeError, match="missing.lcm"):
        sextant.read_log(str(tmp_path / "missing.lcm"))


def test_replay_reads_a_module_written_log(tmp_path):
    """`sextant replay` of a log written from dicts: every odometry message becomes a fused pose."""
    log = tmp_path / "square.lcm"
    cov = [0.0] * 36
    for i in range(6):
        cov[i * 7] = 1e-4
    with sextant.LogWriter(str(log)) as w:
        for k in range(50):
            t = 1_700_000_000_000_000 + k * 100_000
            w.write_message(t, "ODOMETRY", "odometry_t", {
                "utime": t, "sender": "py", "seq": k, "source": "wheel", "planar": True,
                "position": [0.1 * k, 0.0, 0.0], "orientation": [1.0, 0.0, 0.0, 0.0], "covariance": cov})
    out = tmp_path / "out.lcm"
    config = os.path.join(SOURCE, "config", "default.yaml")
    tool("replay", log, "--config", config, "--out-log", out)
    fused = [sextant.decode(d) for _, c, d in sextant.read_log(str(out)) if c == "FUSED_POSE"]
    assert len(fused) == 50
    assert fused[-1]["position"][0] == pytest.approx(4.9, abs=1e-6)


def _damaged_copy(src, dst):
    """`src` with the data length of its 40th event set to 16 MiB: one corrupt header the reader skips over."""
    b = bytearray(open(src, "rb").read())
    pos = 0
    for _ in range(40):
        clen, dlen = struct.unpack_from(">ii", b, pos + 20)
        pos += 28 + clen + dlen
    b[pos + 24:pos + 28] = struct.pack(">i", 1 << 24)
    open(dst, "wb").write(b)


def test_a_damaged_log_is_reported_not_silently_cut(simulated_run, tmp_path):
    clean = str(simulated_run["log"])
    bad = str(tmp_path / "damaged.lcm")
    _damaged_copy(clean, bad)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a clean log warns of nothing
        events = sextant.read_log(clean)
        reader = sextant.LogReader(clean)
        assert list(reader) == events
        assert reader.damage["damaged"] is False
    with pytest.warns(RuntimeWarning, match=r"damaged\.lcm: 1 corrupt event header"):
        got = sextant.read_log(bad)
    assert len(events) - 2 <= len(got) < len(events)  # the events after the damage are read
    reader = sextant.LogReader(bad)
    with pytest.warns(RuntimeWarning, match=r"damaged\.lcm"):
        assert list(reader) == got
    assert reader.damage["damaged"] is True
    assert reader.damage["bad_events"] == 1
    assert reader.damage["skipped_bytes"] > 0
    assert reader.damage["first_problems"][0].startswith("byte ")
