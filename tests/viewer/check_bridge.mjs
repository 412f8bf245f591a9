// Compares what bridge_client.mjs received from `sextant foxglove` with the LCM bus of the same run (recorded by
// lcm-logger, decoded by LCM's Python decoders: lcm_to_json.py).
//
// Usage: node check_bridge.mjs CLIENT.json BUS.jsonl [KERNEL_DROPS]
// - no validation failure, no status error, and the topics a user expects were advertised and delivered;
// - each sextant channel's as-is messages equal the bus messages of that channel, in order, from the client's first
//   one on: every message after the subscription took effect arrived (nothing dropped for a viewer that keeps up),
//   but for datagrams the kernel dropped at the bridge's socket before it could read them: KERNEL_DROPS, the count
//   the bridge reports (/proc/net/udp), bounds what may be missing in all; without it, 1 % per channel;
// - each FUSED_POSE message on the bus has its PoseInFrame on /sextant/<source>/<estimator>/pose with the same
//   time, position and orientation;
// - every frame a pose or a scene entity was drawn in has a path to the display frame "map" through /tf.
import { readFileSync } from "node:fs";

const [clientPath, busPath, kernelDropsArg] = process.argv.slice(2);
const kernelDrops = kernelDropsArg === undefined || kernelDropsArg === "?" ? undefined : Number(kernelDropsArg);
const client = JSON.parse(readFileSync(clientPath, "utf8"));
const bus = readFileSync(busPath, "utf8").split("\n").filter(Boolean).map((l) => JSON.parse(l));
const failures = [...client.failures];
const fail = (what) => failures.push(what);

// Topics a user sees without configuring anything.
for (const topic of ["FUSED_POSE", "/tf", "/sextant/trajectories", "/sextant/targets", "/sextant/bearings", "SEXTANT_STATUS",
  "LANDMARK_MAP", "/sextant/landmark_map", "/sextant/frames"])
  if (!client.counts[topic]) fail(`nothing received on ${topic}`);

// As-is channels, message by message (sender and seq identify one): every message the viewer received equals the
// bus's, and every bus message from the viewer's first one on reached the viewer (the first ones may precede its
// subscription).  lcm-logger, like any LCM receiver on a loaded machine, may itself miss messages the bridge got (at
// the start too): a message the recording lacks is not compared, and at most 1 % of them may be lacking.  JSON.stringify compares values (-0 and 0 alike: the client's file
// holds what JSON.stringify wrote).
const same = (a, b) => JSON.stringify(a) === JSON.stringify(b);
const id = (m) => `${m.sender} ${m.seq}`;
const busBy = new Map(), gotBy = new Map();
for (const e of bus) if (e.message) (busBy.get(e.channel) ?? busBy.set(e.channel, []).get(e.channel)).push(e.message);
for (const r of client.received) if (r.schema.startsWith("sextant.")) (gotBy.get(r.topic) ?? gotBy.set(r.topic, []).get(r.topic)).push(r.message);
let compared = 0, notRecorded = 0, udpLost = 0;
for (const [channel, got] of gotBy) {
  const want = busBy.get(channel) ?? [];
  const wantById = new Map(want.map((m) => [id(m), m]));
  for (const m of got) {
    const b = wantById.get(id(m));
    if (!b) { ++notRecorded; continue; }
    if (!same(b, m)) { fail(`${channel}: ${id(m)} differs:\n  bus:    ${JSON.stringify(b).slice(0, 300)}\n  viewer: ${JSON.stringify(m).slice(0, 300)}`); break; }
    ++compared;
  }
  // The viewer's first message the recording holds (lcm-logger may have missed the very first one).
  const firstRecorded = got.find((m) => wantById.has(id(m)));
  const start = firstRecorded ? want.findIndex((m) => id(m) === id(firstRecorded)) : -1;
  if (start < 0) { fail(`${channel}: none of the viewer's ${got.length} messages is in the recording`); continue; }
  if (start > want.length / 5) fail(`${channel}: the first ${start} of ${want.length} bus messages were missed`);
  const gotIds = new Set(got.map(id));
  const missed = want.slice(start).filter((m) => !gotIds.has(id(m)));
  // The bridge's own drops are counted and must be none (bridge_live.sh checks its counters); what is left is UDP
  // loss before the bridge, which a loaded machine causes in bursts: bounded below by the kernel's own count.
  if (kernelDrops === undefined && missed.length > Math.max(2, (want.length - start) / 100))
    fail(`${channel}: ${missed.length} of ${want.length - start} bus messages after the first received one never reached the viewer (first: ${id(missed[0])})`);
  udpLost += missed.length;
}
if (kernelDrops !== undefined && udpLost > kernelDrops)
  fail(`${udpLost} bus messages never reached the viewer, but the kernel dropped only ${kernelDrops} datagrams at the bridge's socket`);
if (notRecorded > Math.max(10, compared / 100)) fail(`${notRecorded} messages the viewer got are missing from the recording (lcm-logger lost them)`);

// Poses: every FUSED_POSE as-is message received after its PoseInFrame topic's first one has its PoseInFrame,
// equal to it.
const poses = new Map(), firstPose = new Map();
for (const r of client.received)
  if (r.schema === "foxglove.PoseInFrame") {
    const t = r.message.timestamp;
    const utime = t.sec * 1e6 + t.nsec / 1e3;
    poses.set(`${r.topic} ${utime}`, r.message.pose);
    firstPose.set(r.topic, Math.min(firstPose.get(r.topic) ?? Infinity, utime));
  }
let posesChecked = 0;
for (const m of gotBy.get("FUSED_POSE") ?? []) {
  const topic = `/sextant/${m.source}/${m.estimator}/pose`;
  if (!(m.utime >= firstPose.get(topic))) continue;
  const pose = poses.get(`${topic} ${m.utime}`);
  if (!pose) { fail(`no PoseInFrame for ${m.source}/${m.estimator} at ${m.utime}`); continue; }
  const [w, x, y, z] = m.orientation, n = Math.hypot(w, x, y, z);
  const want = { position: { x: m.position[0], y: m.position[1], z: m.position[2] }, orientation: { x: x / n, y: y / n, z: z / n, w: w / n } };
  const close = (a, b) => Math.abs(a - b) <= 1e-12 * Math.max(1, Math.abs(b));
  for (const part of ["position", "orientation"])
    for (const k of Object.keys(want[part]))
      if (!close(pose[part][k], want[part][k])) { fail(`${m.source}/${m.estimator} at ${m.utime}: ${part}.${k} ${pose[part][k]} != ${want[part][k]}`); break; }
  ++posesChecked;
}
if (posesChecked === 0) fail("no pose checked");

// Frames: each one drawn in reaches "map" through the parents /tf gave, with no cycle.
const rooted = (frame) => {
  for (let f = frame, steps = 0; f !== "map"; f = client.parents[f], ++steps)
    if (f === undefined || steps > Object.keys(client.parents).length) return false;
  return true;
};
if (!client.drawnIn.length) fail("no pose or scene entity received");
for (const f of client.drawnIn) if (!rooted(f)) fail(`frame ${f} has no path to map through /tf`);

console.log(`check_bridge: ${client.channels.length} channels, ${compared} as-is messages equal to the bus's ` +
  `(${notRecorded} not in the recording, ${udpLost} on the bus not received by the bridge), ${posesChecked} poses checked, frames ${client.drawnIn.join(" ")} all reach map`);
if (failures.length) { for (const f of failures.slice(0, 20)) console.error(`FAIL: ${f}`); process.exit(1); }
console.log("check_bridge: ok");
