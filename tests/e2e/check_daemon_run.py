"""Checks a live sextantd run against the simulated log it was fed and against a deterministic replay.

Usage: check_daemon_run.py SENT.lcm RECORD.lcm BUS.lcm REPLAYED.lcm
  SENT.lcm      the simulated log that lcm-logplayer played
  RECORD.lcm    sextantd's own --record file (everything it saw on the bus, its own outputs included)
  BUS.lcm       lcm-logger's recording of the bus
  REPLAYED.lcm  `sextant replay SENT.lcm --out-log` (what the engine publishes offline)
"""
import sys

from lcmlog import read_log
from sextant import fused_pose_t, odometry_t, status_t, targets_t, truth_t

INPUTS = ("ODOMETRY", "LANDMARKS", "BEARINGS", "LOOP_CLOSURES", "GROUND_TRUTH")


def bearing_scan_id(data):
    from sextant import bearing_scan_t
    return bearing_scan_t.decode(data).scan_id


def main():
    sent_path, rec_path, bus_path, replay_path = sys.argv[1:5]
    errors = []
    sent = [(c, b) for _, c, b in read_log(sent_path)]
    rec = [(c, b) for _, c, b in read_log(rec_path)]
    bus = [(c, b) for _, c, b in read_log(bus_path)]

    # The recording is complete: every message that was played is in it, byte for byte.
    sent_inputs = sorted(x for x in sent if x[0] in INPUTS)
    rec_inputs = sorted(x for x in rec if x[0] in INPUTS)
    if sent_inputs != rec_inputs:
        errors.append(f"recording has {len(rec_inputs)} input messages, {len(sent_inputs)} were played")

    odometry = [odometry_t.decode(b) for c, b in sent if c == "ODOMETRY"]
    live = [fused_pose_t.decode(b) for c, b in rec if c == "FUSED_POSE"]
    offline = [fused_pose_t.decode(b) for _, c, b in read_log(replay_path) if c == "FUSED_POSE"]
    on_bus = [fused_pose_t.decode(b) for c, b in bus if c == "FUSED_POSE"]

    # Count and order: one fused pose per odometry message, strictly increasing utime, consecutive seq.
    if len(live) != len(odometry):
        errors.append(f"{len(live)} FUSED_POSE for {len(odometry)} odometry messages")
    if [f.utime for f in live] != [o.utime for o in odometry]:
        errors.append("FUSED_POSE utimes differ from the odometry utimes")
    if [f.seq for f in live] != list(range(len(live))):
        errors.append("FUSED_POSE sequence numbers are not 0, 1, 2, ...")
    if any(f.sender != "sextantd" or f.estimator != "dead_reckoning" for f in live):
        errors.append("FUSED_POSE sender/estimator wrong")

    # Values: the live daemon publishes exactly what the deterministic replay computes.
    if len(offline) != len(live):
        errors.append(f"replay published {len(offline)} FUSED_POSE, the daemon {len(live)}")
    # Byte for byte but for lag_us: the daemon's wall clock at publication minus utime live, 0 in replay.
    if any(b.lag_us != 0 for b in offline):
        errors.append("replay published a FUSED_POSE with a lag (it has no real time: 0)")
    for a in live:
        a.lag_us = 0
    mismatched = sum(1 for a, b in zip(live, offline) if a.encode() != b.encode())
    if mismatched:
        errors.append(f"{mismatched} FUSED_POSE messages differ between the live run and the replay")

    # The other estimator (the EKF) is published beside it.
    ekf = [fused_pose_t.decode(b) for c, b in rec if c == "FUSED_POSE_EKF"]
    if len(ekf) != len(odometry) or any(f.estimator != "ekf" for f in ekf):
        errors.append(f"{len(ekf)} FUSED_POSE_EKF messages for {len(odometry)} odometry messages")

    # Bearing scans in, TARGETS out: near the simulated targets' true positions.
    targets = [targets_t.decode(b) for c, b in rec if c == "TARGETS"]
    scan_ids = {bearing_scan_id(b) for c, b in sent if c == "BEARINGS"}
    truth = {}
    for c, b in sent:
        if c == "GROUND_TRUTH":
            t = truth_t.decode(b)
            if t.kind == "target":
                truth.setdefault(t.utime, []).append(t.position)
    if len(targets) < len(scan_ids) - 1:
        errors.append(f"{len(targets)} TARGETS messages for {len(scan_ids)} scans")
    found = total = estimates = ghosts = 0
    near = lambda x, p: sum((a - b) ** 2 for a, b in zip(x, p)) < 1.0
    for m in targets:
        for p in truth.get(m.utime, []):
            total += 1
            found += any(near(t.position, p) for t in m.targets)
        for t in m.targets:  # an estimate farther than 1 m from every true target (false alarms or a wrong tuple)
            estimates += 1
            ghosts += not any(near(t.position, p) for p in truth.get(m.utime, []))
    if total == 0 or found < 0.9 * total:
        errors.append(f"TARGETS found {found} of {total} true targets within 1 m")
    if ghosts > 0.15 * estimates:
        errors.append(f"TARGETS: {ghosts} of {estimates} estimates are ghosts (farther than 1 m from every true target)")

    # What another process sees on the bus (lcm-logger may lose a few datagrams under load).
    if len(on_bus) < 0.95 * len(live):
        errors.append(f"lcm-logger saw only {len(on_bus)} of {len(live)} FUSED_POSE")

    # Status: published regularly; the last one accounts for every input and output.
    statuses = [status_t.decode(b) for c, b in rec if c == "SEXTANT_STATUS"]
    if len(statuses) < 3:
        errors.append(f"only {len(statuses)} status messages")
    else:
        final = statuses[-1]
        ch = {c.channel: c for c in final.channels}
        for name in ("ODOMETRY", "LANDMARKS", "BEARINGS", "LOOP_CLOSURES"):
            n = sum(1 for c, _ in sent if c == name)
            c = ch.get(name)
            if c is None or c.received != n or c.decoded != n or c.rejected != 0 or c.dropped != 0:
                errors.append(f"status for {name}: expected {n} received and decoded, got "
                              f"{None if c is None else (c.received, c.decoded, c.rejected, c.dropped)}")
        stage = {s.name: s for s in final.stages}.get("dead_reckoning")
        if stage is None or stage.processed != len(odometry):
            errors.append("status: dead_reckoning did not process every odometry message")
        elif not (0 <= stage.latency_ms_p50 <= stage.latency_ms_p99 <= stage.latency_ms_max):
            errors.append("status: latency percentiles out of order")
        outs = dict(zip(final.output_channels, final.output_counts))
        if outs.get("FUSED_POSE") != len(odometry):
            errors.append(f"status: {outs.get('FUSED_POSE')} FUSED_POSE published")
        uptimes = [s.uptime_s for s in statuses]
        if any(b <= a for a, b in zip(uptimes, uptimes[1:])):
            errors.append("status uptime not increasing")

    print(f"TARGETS: {len(targets)} messages, {found} of {total} true targets found within 1 m, {ghosts} ghosts of {estimates} estimates")
    print(f"played {len(sent)} messages ({len(odometry)} odometry); recorded {len(rec)}; FUSED_POSE live "
          f"{len(live)}, replay {len(offline)}, lcm-logger {len(on_bus)}; {len(statuses)} status messages")
    if errors:
        print("FAILED:\n  " + "\n  ".join(errors))
        sys.exit(1)


if __name__ == "__main__":
    main()
