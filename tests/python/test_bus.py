"""sextant.Bus: publish and subscribe through liblcm.  In process over LCM's memq:// provider, and live: sextantd
in a private network namespace (its loopback carrying the multicast, as tests/e2e/netns.bash sets up) fed from
Python, its fused poses and status received in Python and checked against a deterministic replay."""
import os
import signal
import subprocess
import sys
import time

import pytest
import sextant

from conftest import BIN, tool

LIVE_URL = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"


def test_memq_publish_subscribe():
    got = []
    with sextant.Bus("memq://") as bus:
        sub = bus.subscribe("ODO.*", lambda ch, t, m: got.append((ch, t, m)))
        raw = []
        bus.subscribe("OTHER", lambda ch, data: raw.append((ch, data)), raw=True)
        bus.publish_message("ODOMETRY", "odometry_t", {"utime": 42, "source": "wheel"})
        bus.publish("ODOM2", b"not a sextant message")
        bus.publish("OTHER", sextant.encode("truth_t", {"utime": 7}))
        bus.publish("UNWATCHED", b"x")
        while bus.handle(timeout=0.2):
            pass
        assert [(c, t) for c, t, _ in got] == [("ODOMETRY", "odometry_t"), ("ODOM2", None)]
        assert got[0][2]["utime"] == 42 and got[0][2]["source"] == "wheel"
        assert got[1][2] == b"not a sextant message"
        assert raw == [("OTHER", sextant.encode("truth_t", {"utime": 7}))]
        bus.unsubscribe(sub)
        bus.publish_message("ODOMETRY", "odometry_t", {"utime": 43})
        bus.handle(timeout=0.2)
        assert len(got) == 2
        with pytest.raises(ValueError, match="no subscription"):
            bus.unsubscribe(sub)


def test_callback_errors_reach_the_caller():
    with sextant.Bus("memq://") as bus:
        def broken(channel, type_name, msg):
            raise KeyError("from the callback")
        bus.subscribe("X", broken)
        bus.publish_message("X", "truth_t", {})
        with pytest.raises(KeyError, match="from the callback"):
            bus.handle(timeout=1.0)
        assert bus.handle(timeout=0.05) is False  # nothing left, no stale error


def test_bad_url_explains_the_bus():
    with pytest.raises(RuntimeError, match="224.0.0.0/4"):
        sextant.Bus("nosuchprovider://")
    bus = sextant.Bus("memq://")
    bus.close()
    with pytest.raises(ValueError, match="closed"):
        bus.publish("X", b"")


def in_namespace():
    return os.environ.get("SEXTANT_IN_NETNS") == "1"


def rerun_in_namespace(test):
    """Runs this file's `test` again in a private network namespace; fails with its output when it fails there."""
    if subprocess.run(["unshare", "--net", "true"], capture_output=True).returncode != 0:
        pytest.skip("cannot create a network namespace (unshare --net needs root or user namespaces)")
    r = subprocess.run(
        ["unshare", "--net", "bash", "-c",
         'ip link set lo up && ip route add 224.0.0.0/4 dev lo && exec "$@"', "in_netns",
         sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", f"{__file__}::{test}"],
        env=dict(os.environ, SEXTANT_IN_NETNS="1", LCM_DEFAULT_URL=LIVE_URL), capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "1 passed" in r.stdout, r.stdout


def test_live_queue_capacity():
    """Over UDP multicast, liblcm queues at most 30 messages per subscription by its default and drops the rest
    silently; subscribe() asks for 10000, so a burst waits for handle() instead of vanishing."""
    if not in_namespace():
        return rerun_in_namespace("test_live_queue_capacity")
    counts = {}
    for capacity in (30, None):
        got = []
        with sextant.Bus() as bus:
            if capacity:
                bus.subscribe("BURST", lambda ch, data: got.append(data), raw=True, queue_capacity=capacity)
            else:
                bus.subscribe("BURST", lambda ch, data: got.append(data), raw=True)
            for k in range(500):
                bus.publish("BURST", k.to_bytes(4, "big"))
            time.sleep(0.5)  # every datagram is in liblcm's queue (or dropped) before the first handle()
            while bus.handle(timeout=0.3):
                pass
        counts[capacity] = len(got)
    assert counts[None] == 500, counts
    assert counts[30] <= 31, counts  # liblcm's own default would have lost the rest


def test_live_daemon(tmp_path):
    if not in_namespace():
        return rerun_in_namespace("test_live_daemon")

    log = tmp_path / "run.lcm"
    tool("simulate", "planar", "-o", log, "--seed", 4, "--duration", 20)
    config = tmp_path / "config.yaml"
    config.write_text("daemon:\n  status_period_s: 0.2\nengine:\n  primary_estimator: dead_reckoning\n")
    replayed = tmp_path / "replayed.lcm"
    tool("replay", log, "--config", config, "--out-log", replayed)
    expected = [d for _, c, d in sextant.read_log(str(replayed)) if c == "FUSED_POSE"]
    inputs = [(ts, c, d) for ts, c, d in sextant.read_log(str(log))
              if c in ("ODOMETRY", "LANDMARKS", "BEARINGS", "LOOP_CLOSURES")]
    assert len(expected) > 100

    fused, statuses = [], []
    with sextant.Bus() as bus:
        bus.subscribe("FUSED_POSE", lambda ch, data: fused.append(data), raw=True)
        bus.subscribe("SEXTANT_STATUS", lambda ch, t, m: statuses.append(m))
        daemon_log = open(tmp_path / "daemon.log", "w+")
        daemon = subprocess.Popen([os.path.join(BIN, "sextantd"), "--config", str(config)],
                                  stdout=daemon_log, stderr=subprocess.STDOUT)
        try:
            deadline = time.monotonic() + 60
            while not statuses:  # running: its first status is on the bus
                assert daemon.poll() is None, open(tmp_path / "daemon.log").read()
                assert time.monotonic() < deadline, "no SEXTANT_STATUS from sextantd"
                bus.handle(timeout=0.1)
            # Play the inputs at 8x their pace, handling what comes back in between.
            t0, w0 = inputs[0][0], time.monotonic()
            for ts, channel, data in inputs:
                while time.monotonic() - w0 < (ts - t0) / 8e6:
                    bus.handle(timeout=0.002)
                bus.publish(channel, data)
            deadline = time.monotonic() + 30
            while len(fused) < len(expected) and time.monotonic() < deadline:
                bus.handle(timeout=0.1)
            n_status = len(statuses)
            while len(statuses) < n_status + 2 and time.monotonic() < deadline:
                bus.handle(timeout=0.1)
        finally:
            daemon.send_signal(signal.SIGTERM)
            rc = daemon.wait(timeout=30)
    assert rc == 0, open(tmp_path / "daemon.log").read()
    last = statuses[-1]
    odo = {c["channel"]: c for c in last["channels"]}["ODOMETRY"]
    assert odo["received"] == sum(1 for _, c, _ in inputs if c == "ODOMETRY"), "the daemon did not receive every input"
    assert odo["decoded"] == odo["received"] and odo["rejected"] == 0 and odo["dropped"] == 0
    assert len(fused) == len(expected)
    # The same poses byte for byte but for lag_us: the live daemon's is its wall clock at publication minus utime
    # (the simulated run's times are not the wall clock's: large), replay's is 0 (it has no real time).
    live, replay = [sextant.decode(d) for d in fused], [sextant.decode(d) for d in expected]
    assert all(m.pop("lag_us") == 0 for m in replay)
    lags = [m.pop("lag_us") for m in live]
    assert live == replay, "the live daemon's FUSED_POSE differ from the deterministic replay's"
    assert all(lag != 0 for lag in lags)
    assert last["version"] == sextant.__version__
    assert last["sender"] == "sextantd"
