"""Run with lcm-gen's Python classes for the sextant package on PYTHONPATH (build/lcmtypes/python): decodes every
event of an LCM log whose channel names its message type with those classes, and prints one JSON line per event:
the fields as plain values and the bytes lcm-gen's encoder makes of them again.  An encoder and decoder independent
of the sextant module, to check it against."""
import json
import struct
import sys

import sextant  # lcm-gen's package (not the module under test)


def plain(v):
    if isinstance(v, list):
        return [plain(x) for x in v]
    if hasattr(v, "__slots__"):
        return {k: plain(getattr(v, k)) for k in v.__slots__}
    if isinstance(v, bytes):
        return list(v)
    return v


def read_log(path):
    data = open(path, "rb").read()
    pos = 0
    while pos + 28 <= len(data):
        sync, _num, ts, clen, dlen = struct.unpack_from(">IqqII", data, pos)
        assert sync == 0xEDA1DA01, f"bad sync word at byte {pos}"
        pos += 28
        channel = data[pos:pos + clen].decode()
        pos += clen
        yield ts, channel, data[pos:pos + dlen]
        pos += dlen


for ts, channel, data in read_log(sys.argv[1]):
    msg = getattr(sextant, channel).decode(data)
    print(json.dumps({"timestamp": ts, "channel": channel, "fields": plain(msg), "reencoded": msg.encode().hex()}))
