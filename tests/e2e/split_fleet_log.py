"""Splits a fleet's log into one log per robot, as one robot's computer would see its own sensors: the odometry,
landmark sightings and loop closures whose `source` is that robot, on channels named with the robot's prefix
(PREFIX + channel).  Everything else (ground truth, bearings) is left out.

Usage: split_fleet_log.py IN.lcm OUT_DIR ROBOT=PREFIX ...   writes OUT_DIR/ROBOT.lcm for each robot and prints the
number of messages each got."""
import os
import sys

from lcmlog import read_log, write_event
from sextant import landmarks_t, loop_closure_t, odometry_t

DECODERS = {"ODOMETRY": odometry_t, "LANDMARKS": landmarks_t, "LOOP_CLOSURES": loop_closure_t}


def main():
    src, out_dir, pairs = sys.argv[1], sys.argv[2], sys.argv[3:]
    prefixes = dict(p.split("=", 1) for p in pairs)
    files = {robot: open(os.path.join(out_dir, robot + ".lcm"), "wb") for robot in prefixes}
    counts = {robot: 0 for robot in prefixes}
    for ts, channel, data in read_log(src):
        decoder = DECODERS.get(channel)
        if decoder is None:
            continue
        robot = decoder.decode(data).source
        if robot not in files:
            continue
        write_event(files[robot], counts[robot], ts, prefixes[robot] + channel, data)
        counts[robot] += 1
    for f in files.values():
        f.close()
    for robot in sorted(counts):
        print(f"{robot}: {counts[robot]} messages")
    if any(n == 0 for n in counts.values()):
        sys.exit("a robot got no message")


if __name__ == "__main__":
    main()
