"""Checks a sextantd run fed with make_bad_log.py's log: every rejection counted by reason, all accounting exact.

Usage: check_bad_input.py EXPECTED.json BUS.lcm [--exact RECORD.lcm SENT.lcm | --overload]
BUS.lcm is lcm-logger's recording of the bus; the last SEXTANT_STATUS in it is the daemon's final report.
--exact: a run at the recorded pace: every message sent must have been received, none dropped, and the daemon's
own recording (--record RECORD.lcm) must hold every input message that was sent, byte for byte.
--overload: a run far faster than the daemon's queue allows: the kernel may lose datagrams before the daemon sees
them (invisible to it), so only the daemon's own accounting is checked, and drops must have happened.
In both, lcm-logger itself may lose a few of the daemon's outputs under load; the sequence numbers tell which.
"""
import json
import sys

from lcmlog import read_log
from sextant import status_t, fused_pose_t


def main():
    expected = json.load(open(sys.argv[1]))
    bus = sys.argv[2]
    exact = "--exact" in sys.argv
    overload = "--overload" in sys.argv
    statuses = [status_t.decode(b) for _, c, b in read_log(bus) if c == "SEXTANT_STATUS"]
    fused = [fused_pose_t.decode(b) for _, c, b in read_log(bus) if c == "FUSED_POSE"]
    assert len(statuses) >= 2, f"expected status messages, got {len(statuses)}"
    final = statuses[-1]
    ch = {c.channel: c for c in final.channels}
    odo = ch["ODOMETRY"]
    reasons = dict(zip(odo.reasons, odo.reason_counts))
    sent = expected["valid"] + expected["flood"] + sum(expected["reasons"].values())
    errors = []
    if exact and odo.received != sent:
        errors.append(f"ODOMETRY received {odo.received}, sent {sent}")
    if exact and reasons != expected["reasons"]:
        errors.append(f"rejection reasons {reasons} != expected {expected['reasons']}")
    if not set(reasons) <= set(expected["reasons"]):
        errors.append(f"unexpected rejection reasons {reasons}")
    if odo.received != odo.decoded + odo.rejected:
        errors.append(f"received {odo.received} != decoded {odo.decoded} + rejected {odo.rejected}")
    if exact and odo.decoded != expected["valid"] + expected["flood"]:
        errors.append(f"decoded {odo.decoded} != valid {expected['valid']} + flood {expected['flood']}")
    bear = ch.get("BEARINGS")
    if exact and (bear is None or
                  dict(zip(bear.reasons, bear.reason_counts)).get("too_large") != expected["bearings_rejected"]):
        errors.append("BEARINGS too_large rejections not counted")
    if overload and odo.dropped == 0:
        errors.append("an overloaded queue of 2 dropped nothing")
    stages = {s.name: s for s in final.stages}
    dr = stages["dead_reckoning"]
    if dr.dropped != odo.dropped:
        errors.append(f"stage dropped {dr.dropped} != channel dropped {odo.dropped}")
    if dr.processed + dr.dropped != odo.decoded:
        errors.append(f"processed {dr.processed} + dropped {dr.dropped} != decoded {odo.decoded}")
    seqs = [f.seq for f in fused]
    if len(set(seqs)) != len(seqs) or (seqs and max(seqs) >= dr.processed):
        errors.append("FUSED_POSE sequence numbers repeat or exceed the number of poses processed")
    if not overload and len(fused) < 0.9 * dr.processed:
        errors.append(f"only {len(fused)} of {dr.processed} FUSED_POSE messages reached lcm-logger")
    if exact and odo.dropped != 0:
        errors.append(f"{odo.dropped} events dropped in a run that should drop none")
    if exact:
        rec_path = sys.argv[sys.argv.index("--exact") + 1]
        sent_inputs = sorted(b for _, c, b in read_log(sys.argv[sys.argv.index("--exact") + 2])
                             if c in ("ODOMETRY", "BEARINGS"))
        recorded = sorted(b for _, c, b in read_log(rec_path) if c in ("ODOMETRY", "BEARINGS"))
        if recorded != sent_inputs:
            errors.append(f"recording holds {len(recorded)} input messages, {len(sent_inputs)} were sent")
    utimes = [f.utime for f in fused]
    if any(b <= a for a, b in zip(utimes, utimes[1:])):
        errors.append("FUSED_POSE utimes not strictly increasing")
    if any(f.position[0] != f.position[0] for f in fused):
        errors.append("NaN in a published pose")
    outputs = dict(zip(final.output_channels, final.output_counts))
    if outputs.get("FUSED_POSE") != dr.processed:
        errors.append(f"status says {outputs.get('FUSED_POSE')} FUSED_POSE published, {dr.processed} processed")
    print(f"received {odo.received} decoded {odo.decoded} rejected {odo.rejected} {reasons} "
          f"dropped {odo.dropped} fused {len(fused)} statuses {len(statuses)}")
    if errors:
        print("FAILED:\n  " + "\n  ".join(errors))
        sys.exit(1)


if __name__ == "__main__":
    main()
