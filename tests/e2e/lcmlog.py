"""Reads and writes LCM log files (lcm-logger's format) and decodes sextant messages, for the end-to-end checks.

Format: each event is a 0xEDA1DA01 sync word, int64 event number, int64 timestamp (us), int32 channel length,
int32 data length, the channel name and the data, all big-endian.
"""
import struct


def write_event(f, num, ts, channel, data):
    """Writes one event (number `num`, timestamp `ts` in us, `channel`, the bytes `data`) to the open file `f`."""
    ch = channel.encode()
    f.write(struct.pack(">IqqII", 0xEDA1DA01, num, ts, len(ch), len(data)))
    f.write(ch)
    f.write(data)


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


class TrajectoryRebuild:
    """Rebuilds each body's current trajectory from TRAJECTORY messages (sextant.trajectory_t), by the rule the .lcm
    file states: feed the messages in seq order; keyframes replace those with their ids, removed_ids are erased, and a
    SNAPSHOT chunk is authoritative for its id range [range_first, range_last].  `keyframes(source)` gives the
    keyframe_t objects by increasing id."""

    SNAPSHOT = 1

    def __init__(self):
        self.bodies = {}

    def add(self, m):
        body = self.bodies.setdefault((m.sender, m.source), {})
        if m.kind == self.SNAPSHOT:
            carried = {k.id for k in m.keyframes}
            for i in [i for i in body if m.range_first <= i <= m.range_last and i not in carried]:
                del body[i]
        for i in m.removed_ids:
            body.pop(i, None)
        for k in m.keyframes:
            body[k.id] = k
        return self

    def keyframes(self, source, sender=None):
        for (snd, src), body in self.bodies.items():
            if src == source and (sender is None or snd == sender):
                return [body[i] for i in sorted(body)]
        return []

    def sources(self):
        return sorted({src for _, src in self.bodies})


def rebuild_trajectories(messages):
    """A TrajectoryRebuild fed with decoded trajectory_t messages (in the order given: a log's order is seq order)."""
    r = TrajectoryRebuild()
    for m in messages:
        r.add(m)
    return r
