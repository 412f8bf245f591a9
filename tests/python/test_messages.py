"""Every sextant message to a dict and back, checked against lcm-gen's own Python encoder and decoder; strict
errors naming the field; decoding by fingerprint; the daemon's validation of input messages."""
import json
import math
import os
import random
import subprocess
import sys

import pytest
import sextant

from conftest import LCMTYPES_PY, SOURCE

LIMITS = {"int8_t": 7, "int16_t": 15, "int32_t": 31, "int64_t": 63}


def lcm_files_types():
    return sorted(f[:-4] for f in os.listdir(os.path.join(SOURCE, "lcmtypes", "sextant")) if f.endswith(".lcm"))


def random_value(t, rng):
    if t in LIMITS:
        b = LIMITS[t]
        return rng.choice([-(2 ** b), 2 ** b - 1, 0, rng.randint(-(2 ** b), 2 ** b - 1)])
    if t == "double":
        return rng.choice([rng.uniform(-1e6, 1e6), rng.uniform(-1, 1) * 1e-300, 1.0 / 3.0, -0.0, math.inf])
    if t == "float":
        return rng.randint(-1000, 1000) / 8.0  # exact in 32 bits
    if t == "string":
        return "".join(rng.choice("abcXYZ_ 0é→") for _ in range(rng.randint(0, 12)))
    if t == "boolean":
        return rng.random() < 0.5
    if t == "byte":
        return rng.randint(0, 255)
    assert t.startswith("sextant."), t
    return random_message(t.split(".", 1)[1], rng)


def random_message(type_name, rng):
    fields = sextant.message_fields(type_name)
    lengths = {dim: rng.randint(0, 3) for _, _, dim in fields if dim and not dim.isdigit()}
    d = {}
    for name, t, dim in fields:
        if name in lengths:
            continue  # a length field follows its lists
        if not dim:
            d[name] = random_value(t, rng)
        else:
            d[name] = [random_value(t, rng) for _ in range(int(dim) if dim.isdigit() else lengths[dim])]
    return d


def with_lengths(type_name, d):
    """d as decoding gives it back: the length fields filled in, nested messages too."""
    out = {}
    fields = sextant.message_fields(type_name)
    for name, t, dim in fields:
        if name in d:
            v = d[name]
            if t.startswith("sextant."):
                nested = t.split(".", 1)[1]
                v = [with_lengths(nested, x) for x in v] if dim else with_lengths(nested, v)
            out[name] = v
    for name, t, dim in fields:
        if dim and not dim.isdigit():
            out[dim] = len(d[name])
    return {name: out[name] for name, _, _ in fields}


def test_every_lcm_file_has_a_type():
    assert sorted(sextant.message_types()) == lcm_files_types()


def test_version_field_follows_seq_in_status():
    names = [f[0] for f in sextant.message_fields("status_t")]
    assert names[names.index("seq") + 1] == "version"


@pytest.mark.parametrize("type_name", lcm_files_types())
def test_round_trip(type_name):
    rng = random.Random(type_name)
    for _ in range(20):
        d = random_message(type_name, rng)
        data = sextant.encode(type_name, d)
        assert sextant.message_type(data) == type_name
        assert sextant.decode(data) == with_lengths(type_name, d)
        assert sextant.decode(data, type=type_name) == with_lengths(type_name, d)


def test_empty_dict_is_the_zero_message():
    d = sextant.decode(sextant.encode("odometry_t", {}))
    assert d["utime"] == 0 and d["sender"] == "" and d["planar"] is False
    assert d["position"] == [0.0] * 3 and d["covariance"] == [0.0] * 36


def test_against_lcm_gen(tmp_path):
    """sextant.encode's bytes decode with lcm-gen's classes to the same values, and lcm-gen re-encodes those values
    to the same bytes."""
    assert LCMTYPES_PY and os.path.isdir(LCMTYPES_PY), "SEXTANT_LCMTYPES_PY must name lcm-gen's Python output"
    rng = random.Random(7)
    log = tmp_path / "all.lcm"
    sent = []
    with sextant.LogWriter(str(log)) as w:
        for t in sextant.message_types():
            for k in range(5):
                d = random_message(t, rng)
                data = sextant.encode(t, d)
                w.write(1000 + len(sent), t, data)
                sent.append((t, d, data))
    env = dict(os.environ, PYTHONPATH=LCMTYPES_PY)
    out = subprocess.run([sys.executable, os.path.join(os.path.dirname(__file__), "lcmgen_dump.py"), str(log)],
                         env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    got = [json.loads(line) for line in out.stdout.splitlines()]
    assert len(got) == len(sent)
    for (t, d, data), g in zip(sent, got):
        assert g["channel"] == t
        assert g["fields"] == with_lengths(t, d), t
        assert bytes.fromhex(g["reencoded"]) == data, t


def test_decode_errors():
    with pytest.raises(ValueError, match="fingerprint matches none"):
        sextant.decode(b"\x00" * 16)
    data = sextant.encode("odometry_t", {"utime": 5})
    with pytest.raises(ValueError, match="cannot decode .* as odometry_t"):
        sextant.decode(data[:-3])
    with pytest.raises(ValueError, match="cannot decode .* as landmarks_t"):
        sextant.decode(data, type="landmarks_t")
    with pytest.raises(ValueError, match="unknown message type 'nope_t'"):
        sextant.decode(data, type="nope_t")
    assert sextant.message_type(b"xyz") is None


@pytest.mark.parametrize("message,error", [
    ({"utim": 1}, r"odometry_t: unknown field 'utim'"),
    ({"utime": 1.5}, r"odometry_t.utime: expected an integer, got float"),
    ({"utime": 2 ** 63}, r"odometry_t.utime: 9223372036854775808 is out of range"),
    ({"planar": 1}, r"odometry_t.planar: expected True or False, got int"),
    ({"position": [1, 2]}, r"odometry_t.position: expected 3 values, got 2"),
    ({"position": [1, "x", 3]}, r"odometry_t.position\[1\]: expected a number, got str"),
    ({"source": 3}, r"odometry_t.source: expected a str, got int"),
])
def test_encode_errors_name_the_field(message, error):
    with pytest.raises(ValueError, match=error):
        sextant.encode("odometry_t", message)


def test_encode_errors_in_nested_and_sized_arrays():
    with pytest.raises(ValueError, match=r"status_t.channels\[1\]: unknown field 'bogus'"):
        sextant.encode("status_t", {"channels": [{}, {"bogus": 1}]})
    with pytest.raises(ValueError, match=r"status_t.num_outputs: 3 but output_channels has 1 entries"):
        sextant.encode("status_t", {"num_outputs": 3, "output_channels": ["A"], "output_counts": [1], "output_bytes": [1],
                                    "output_bytes_per_s": [1.0]})
    with pytest.raises(ValueError, match=r"output_channels has 1 entries but output_counts has 2"):
        sextant.encode("status_t", {"output_channels": ["A"], "output_counts": [1, 2], "output_bytes": [1], "output_bytes_per_s": [1.0]})
    with pytest.raises(ValueError, match=r"status_t.stages\[0\].counter_values\[0\]: expected an integer"):
        sextant.encode("status_t", {"stages": [{"counter_names": ["a"], "counter_values": [0.5]}]})


def identity_odometry(**over):
    cov = [0.0] * 36
    for i in range(6):
        cov[i * 7] = 0.01
    d = {"utime": 1_000_000, "sender": "test", "seq": 1, "source": "wheel", "position": [1.0, 2.0, 0.0],
         "orientation": [1.0, 0.0, 0.0, 0.0], "covariance": cov}
    d.update(over)
    return sextant.encode("odometry_t", d)


def test_validate_as_the_daemon_does():
    assert sextant.validate("odometry", identity_odometry()) is None
    reason, message = sextant.validate("odometry", identity_odometry(orientation=[2.0, 0.0, 0.0, 0.0]))
    assert reason == "quaternion" and "orientation" in message
    reason, message = sextant.validate("odometry", identity_odometry(position=[math.nan, 0.0, 0.0]))
    assert reason == "non_finite" and "position" in message
    reason, _ = sextant.validate("odometry", identity_odometry(covariance=[0.0] * 36))
    assert reason == "covariance"
    reason, _ = sextant.validate("landmarks", identity_odometry())
    assert reason == "fingerprint"
    with pytest.raises(ValueError, match="unknown input kind"):
        sextant.validate("odometer", identity_odometry())
