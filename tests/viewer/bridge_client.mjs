// A Foxglove viewer stand-in built on the reference client (@foxglove/ws-protocol's FoxgloveClient over `ws`):
// connects to `sextant foxglove`, subscribes to every channel as it is advertised, validates every message against
// the schema its channel advertises and, for Foxglove schemas, against @foxglove/schemas' schema of that name (to
// which the advertised one must be equal), and records what it received for check_bridge.mjs.
//
// Usage: node bridge_client.mjs ws://HOST:PORT OUT.json [--idle SECONDS] [--stall | --bench]
// Prints "connected" once the server's info arrived; exits when no message arrived for --idle seconds (default 3)
// after the first one, or on SIGTERM, writing OUT.json: {channels, counts, failures, received: [{topic, schema,
// receiveTime, message}] for the as-is sextant channels and the PoseInFrame topics, latencies_ms, parents (each /tf
// frame's latest parent), drawnIn (the frames of the poses and scene entities received)}.
// --stall: subscribe to everything but never read from the socket (a stalled viewer for the bridge's queue bound).
// --bench: no validation and no recording, only counts and latencies (bench/foxglove.sh).
// latencies_ms: for each fused_pose_t message, this client's receive time minus the bridge's receive time (the
// message's timestamp): the latency the bridge adds between the bus and the viewer.
import Ajv from "ajv";
import { writeFileSync } from "node:fs";
import { createRequire } from "node:module";
import { isDeepStrictEqual } from "node:util";
import WebSocket from "ws";

const require = createRequire(import.meta.url);
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const foxgloveSchemas = require("@foxglove/schemas/jsonschema");

const [url, outPath, ...rest] = process.argv.slice(2);
const idleSeconds = rest.includes("--idle") ? Number(rest[rest.indexOf("--idle") + 1]) : 3;
const stall = rest.includes("--stall");
const bench = rest.includes("--bench");

// Foxglove's and Lichtblick's JSON Schema parser (parseJsonSchema in their mcap-support) reads the properties of
// every "type": "object" in a channel's schema and fails on the channel when one has none: the paths of such objects.
const objectsWithoutProperties = (schema, path = "") =>
  schema === null || typeof schema !== "object" ? []
    : [...(schema.type === "object" && !schema.properties ? [path || "/"] : []),
      ...Object.entries(schema).flatMap(([k, v]) => objectsWithoutProperties(v, `${path}/${k}`))];
const ajv = new Ajv({ strict: false });
const channels = new Map(); // channel id -> {topic, schemaName, checks}
const subscriptions = new Map(); // subscription id -> channel id
const counts = {};
const failures = [];
const received = [];
const latencies = [];
const parents = {};
const drawnIn = new Set();
let last = 0, first = 0;
const textDecoder = new TextDecoder();

const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
const client = new FoxgloveClient({ ws });
const fail = (what) => { if (failures.length < 50) failures.push(what); };

client.on("serverInfo", (info) => {
  if (info.capabilities.length !== 0) fail(`server offers capabilities ${info.capabilities}`);
  console.log("connected");
});
client.on("status", (s) => fail(`status from the server: ${s.message}`));
client.on("error", (e) => fail(`client error: ${e}`));
const compiled = new Map(); // schema text -> validator (the big SceneUpdate schema is compiled once)
const compile = (schema) => compiled.get(JSON.stringify(schema)) ?? compiled.set(JSON.stringify(schema), ajv.compile(schema)).get(JSON.stringify(schema));
// The Foxglove schemas compiled before connecting, so that advertisements are handled at once.
for (const name of ["PoseInFrame", "FrameTransforms", "SceneUpdate"]) compile(foxgloveSchemas[name]);
client.on("advertise", (list) => {
  // Subscribe to all of them first: compiling schemas takes a while and messages flow only once subscribed.
  for (const ch of list) subscriptions.set(client.subscribe(ch.id), ch.id);
  for (const ch of list) {
    if (bench) { channels.set(ch.id, { topic: ch.topic, schemaName: ch.schemaName, checks: [] }); continue; }
    if (ch.encoding !== "json" || ch.schemaEncoding !== "jsonschema") fail(`${ch.topic}: encoding ${ch.encoding}/${ch.schemaEncoding}`);
    const own = JSON.parse(ch.schema);
    const checks = [compile(own)];
    for (const path of objectsWithoutProperties(own)) fail(`${ch.schemaName}: the object at ${path} has no properties (the viewers cannot parse it)`);
    if (ch.schemaName.startsWith("foxglove.")) {
      const reference = foxgloveSchemas[ch.schemaName.slice("foxglove.".length)];
      if (!reference) fail(`${ch.schemaName}: not a Foxglove schema`);
      else if (own.title !== ch.schemaName) fail(`${ch.schemaName}: the advertised schema's title is ${own.title}`);
      else checks.push(compile(reference));
    }
    channels.set(ch.id, { topic: ch.topic, schemaName: ch.schemaName, checks });
    if (stall && subscriptions.size === 1) setTimeout(() => ws._socket.pause(), 200); // stop reading the socket
  }
});
client.on("message", ({ subscriptionId, timestamp, data }) => {
  const nowNs = (performance.timeOrigin + performance.now()) * 1e6;
  const now = Date.now();
  last = now;
  if (!first) first = now;
  const ch = channels.get(subscriptions.get(subscriptionId));
  if (!ch) return fail(`message on unknown subscription ${subscriptionId}`);
  const message = JSON.parse(textDecoder.decode(data));
  if (ch.schemaName === "sextant.fused_pose_t") latencies.push((nowNs - Number(timestamp)) / 1e6);
  if (bench) { counts[ch.topic] = (counts[ch.topic] ?? 0) + 1; return; }
  for (const check of ch.checks) if (!check(message)) { fail(`${ch.topic}: ${ajv.errorsText(check.errors)}`); break; }
  counts[ch.topic] = (counts[ch.topic] ?? 0) + 1;
  if (ch.schemaName === "foxglove.FrameTransforms") for (const t of message.transforms) parents[t.child_frame_id] = t.parent_frame_id;
  if (ch.schemaName === "foxglove.PoseInFrame") drawnIn.add(message.frame_id);
  if (ch.schemaName === "foxglove.SceneUpdate") for (const e of message.entities) drawnIn.add(e.frame_id);
  if (ch.schemaName.startsWith("sextant.") || ch.schemaName === "foxglove.PoseInFrame")
    received.push({ topic: ch.topic, schema: ch.schemaName, receiveTime: Number(timestamp), message });
});

function finish() {
  writeFileSync(outPath, JSON.stringify({ channels: [...channels.values()].map(({ topic, schemaName }) => ({ topic, schemaName })),
    counts, failures, received, latencies_ms: latencies, parents, drawnIn: [...drawnIn] }));
  client.close();
  process.exit(0);
}
process.on("SIGTERM", finish);
setInterval(() => { if (!stall && first && Date.now() - last > idleSeconds * 1000) finish(); }, 100);  // also keeps a stalled client alive
