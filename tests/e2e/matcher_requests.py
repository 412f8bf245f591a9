"""Match requests for the simulated matcher's end-to-end test, and the check of its answers.

  matcher_requests.py make SIM.lcm REQUESTS.lcm EXPECTED.json   requests between ground-truth stamps of a planar
      simulated run (answerable), some outside the truth's span, some of an unknown body, some undecodable bytes
  matcher_requests.py check SIM.lcm EXPECTED.json BUS.lcm COUNTS.json [BUS2.lcm]
      every answer on LOOP_CLOSURES answers a request with its ids and times copied (from = b, to = a), is within
      noise of the true planar relative pose (correct) or at least ~1 m / 0.5 rad off it (wrong), the counts printed
      by `sextant matcher --json` agree with the bus, and a second run with the same seed (BUS2) gave the same
      answers.
"""
import json
import math
import random
import sys

from lcmlog import decode_all, read_log, write_event
from sextant import loop_closure_t, match_request_t, truth_t


def robot_truth(sim):
    out = {}
    for m in decode_all(sim, "GROUND_TRUTH", truth_t):
        if m.kind == "robot":
            w, x, y, z = m.orientation
            out[m.utime] = (m.position[0], m.position[1], math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))
    return out


def relative(frm, to):
    """The planar pose `to` in the frame of `frm` (SE(2) frm^-1 to), both (x, y, yaw)."""
    c, s = math.cos(frm[2]), math.sin(frm[2])
    dx, dy = to[0] - frm[0], to[1] - frm[1]
    dyaw = math.atan2(math.sin(to[2] - frm[2]), math.cos(to[2] - frm[2]))
    return (c * dx + s * dy, -s * dx + c * dy, dyaw)


def make(sim, out, expected_path):
    truth = robot_truth(sim)
    stamps = sorted(truth)
    rng = random.Random(7)
    requests, expected = [], {"answerable": 0, "out_of_span": 0, "invalid": 0, "undecodable": 0}
    for i in range(240):
        m = match_request_t()
        m.utime = 0
        m.sender = "matcher-e2e"
        m.seq = i
        m.source = "robot1"
        m.request_id = 1000 + i
        m.kind = "local" if i % 3 else "random"
        ia, ib = sorted(rng.sample(range(len(stamps)), 2), reverse=True)
        m.utime_a, m.utime_b = stamps[ia], stamps[ib]
        m.keyframe_a, m.keyframe_b = ia, ib
        m.position_a = m.position_b = [0.0, 0.0, 0.0]
        m.orientation_a = m.orientation_b = [1.0, 0.0, 0.0, 0.0]
        kind = "answerable"
        if i % 40 == 5:
            m.utime_a = stamps[-1] + 1_000_000  # after the truth ends
            kind = "out_of_span"
        elif i % 40 == 9:
            m.source = "nobody"
            kind = "invalid"
        m.utime = m.utime_a
        expected[kind] += 1
        requests.append(m.encode())
    for i in range(3):
        requests.insert(50 * (i + 1), b"\x00garbage" * (i + 1))
        expected["undecodable"] += 1
    with open(out, "wb") as f:
        for k, data in enumerate(requests):
            write_event(f, k, 1_000_000 + 5000 * k, "MATCH_REQUESTS", data)
    with open(expected_path, "w") as f:
        json.dump(expected, f)


def check(sim, expected_path, bus, counts_path, bus2=None):
    truth = robot_truth(sim)
    expected = json.load(open(expected_path))
    counts = json.load(open(counts_path))
    requests = {}
    for _, channel, data in read_log(bus):
        if channel == "MATCH_REQUESTS" and not data.startswith(b"\x00garbage"):
            m = match_request_t.decode(data)
            requests[m.request_id] = m
    assert len(requests) == 240, f"{len(requests)} requests on the bus"
    answers = decode_all(bus, "LOOP_CLOSURES", loop_closure_t)
    assert counts["requests"] == 240, counts
    assert counts["undecodable"] == expected["undecodable"], counts
    assert counts["out_of_span"] == expected["out_of_span"], counts
    assert counts["invalid"] == expected["invalid"], counts
    assert counts["answered"] + counts["wrong"] + counts["failed"] == expected["answerable"], counts
    assert counts["published"] == counts["answered"] + counts["wrong"] == len(answers), (counts, len(answers))
    assert counts["unsent"] == 0, counts
    assert counts["failed"] > 0 and counts["wrong"] > 0, counts  # 10% each of 228
    wrong = correct = 0
    for a in answers:
        r = requests[a.request_id]
        assert (a.utime_from, a.utime_to, a.keyframe_from, a.keyframe_to) == (r.utime_b, r.utime_a, r.keyframe_b, r.keyframe_a)
        assert a.source == "robot1" and a.planar and a.matcher == "sextant-matcher" and a.sender == "sextant-matcher"
        assert a.position[2] == 0.0
        x, y, yaw = relative(truth[r.utime_b], truth[r.utime_a])
        w, qx, qy, qz = a.orientation
        ayaw = math.atan2(2 * (w * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))
        et = math.hypot(a.position[0] - x, a.position[1] - y)
        er = abs(math.atan2(math.sin(ayaw - yaw), math.cos(ayaw - yaw)))
        if et < 0.25 and er < 0.05:  # 5 sigma of --sigma-t 0.05 / --sigma-r 0.01
            correct += 1
        elif et > 0.7 or er > 0.35:
            wrong += 1
        else:
            raise AssertionError(f"answer {a.request_id} neither near nor far: {et:.3f} m, {er:.3f} rad")
    assert (correct, wrong) == (counts["answered"], counts["wrong"]), (correct, wrong, counts)
    seqs = [a.seq for a in answers]
    assert seqs == list(range(len(answers))), "sequence numbers not 0, 1, 2, ..."
    if bus2:
        again = {a.request_id: (tuple(a.position), tuple(a.orientation)) for a in decode_all(bus2, "LOOP_CLOSURES", loop_closure_t)}
        first = {a.request_id: (tuple(a.position), tuple(a.orientation)) for a in answers}
        assert again == first, "a second run with the same seed answered differently"
    print(f"matcher answers: {correct} correct, {wrong} wrong, {counts['failed']} failed, "
          f"{counts['out_of_span']} out of span, {counts['invalid']} invalid, {counts['undecodable']} undecodable")


if __name__ == "__main__":
    if sys.argv[1] == "make":
        make(*sys.argv[2:5])
    else:
        check(*sys.argv[2:])
