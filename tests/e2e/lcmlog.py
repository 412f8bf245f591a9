"""Reads LCM log files (lcm-logger's format) and decodes sextant messages, for the end-to-end checks.

Format: each event is a 0xEDA1DA01 sync word, int64 event number, int64 timestamp (us), int32 channel length,
int32 data length, the channel name and the data, all big-endian.
"""
import struct


def read_log(path):
    """Yields (timestamp, channel, bytes) for every event of the log at `path`."""
    with open(path, "rb") as f:
        data = f.read()
    pos = 0
    while pos + 28 <= len(data):
        sync, _num, ts, clen, dlen = struct.unpack_from(">IqqII", data, pos)
        if sync != 0xEDA1DA01:
            raise ValueError(f"{path}: bad sync word at byte {pos}")
        pos += 28
        channel = data[pos:pos + clen].decode()
        pos += clen
        payload = data[pos:pos + dlen]
        pos += dlen
        if len(payload) != dlen:
            raise ValueError(f"{path}: truncated event at byte {pos}")
        yield ts, channel, payload


def decode_all(path, channel, msg_type):
    """Every message on `channel` decoded as `msg_type` (an lcm-gen Python class)."""
    return [msg_type.decode(b) for _, c, b in read_log(path) if c == channel]
