// Checks an MCAP file written by sextant with the reference implementation (@mcap/core) and compares its messages
// with the LCM log it came from, decoded by LCM's own Python decoders (lcm_to_json.py).
//
// Usage: node check_mcap.mjs FILE.mcap LOG.jsonl
// - McapIndexedReader opens the file through its summary (summary CRC), reads every message through the chunk
//   indexes and message indexes with chunk CRCs validated; the Statistics record must match what was read (message
//   count, per channel counts, time range, chunk count) and the data section CRC is recomputed over the file;
// - McapStreamReader reads the whole file record by record (the other reference path, with its own checks);
// - every JSON message is valid against its channel's schema (ajv), and each Foxglove view also against the schema
//   of the same name in @foxglove/schemas (sextant's own schema, written for the fields it sends, names the same
//   type: its title must be that name);
// - channel by channel (the "lcm_channel" metadata), the messages equal the log's: same timestamps, same decoded
//   values (raw LCM bytes for what has no JSON form);
// - every frame a pose or a scene entity is drawn in has a path to the display frame "map" through the /tf transforms
//   read so far, by the end of the messages of its log time (the views of one LCM message share its log time), with
//   no cycle;
// - --require-topics T1,T2,...: each of these topics has messages.
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { crc32 } from "@foxglove/crc";
import foxgloveSchemas from "@foxglove/schemas/jsonschema.js";
import Ajv from "ajv";
import { decompress } from "fzstd";
import { createReadStream, readFileSync } from "node:fs";
import { createInterface } from "node:readline";
import { isDeepStrictEqual } from "node:util";

const [mcapPath, jsonlPath, ...options] = process.argv.slice(2);
const required = options.includes("--require-topics") ? options[options.indexOf("--require-topics") + 1].split(",") : [];
const failures = [];
const fail = (what) => {
  if (failures.length < 20) console.error(`FAIL: ${what}`);
  failures.push(what);
};
const bytes = readFileSync(mcapPath);
const readable = {
  size: async () => BigInt(bytes.length),
  read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
};
const decompressHandlers = { zstd: (buffer, size) => decompress(buffer, new Uint8Array(Number(size))) };

// 1. The indexed reader: summary, indexes, statistics, CRCs.
const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
const messages = [];
for await (const m of reader.readMessages({ validateCrcs: true })) messages.push(m);
const stats = reader.statistics;
if (!stats) fail("no Statistics record");
else {
  if (stats.messageCount !== BigInt(messages.length)) fail(`Statistics: ${stats.messageCount} messages, read ${messages.length}`);
  const perChannel = new Map();
  for (const m of messages) perChannel.set(m.channelId, (perChannel.get(m.channelId) ?? 0n) + 1n);
  for (const [id, n] of perChannel)
    if (stats.channelMessageCounts.get(id) !== n) fail(`Statistics: channel ${id} counts ${stats.channelMessageCounts.get(id)}, read ${n}`);
  const times = messages.map((m) => m.logTime);
  const min = times.reduce((a, b) => (b < a ? b : a)), max = times.reduce((a, b) => (b > a ? b : a));
  if (stats.messageStartTime !== min || stats.messageEndTime !== max) fail("Statistics: time range differs from the messages'");
  if (stats.chunkCount !== reader.chunkIndexes.length) fail(`Statistics: ${stats.chunkCount} chunks, ${reader.chunkIndexes.length} chunk indexes`);
  if (stats.channelCount !== reader.channelsById.size) fail("Statistics: channel count differs from the summary's channels");
}
for (let i = 1; i < messages.length; ++i)
  if (messages[i].logTime < messages[i - 1].logTime) { fail("indexed reader: messages out of log-time order"); break; }
if (reader.dataSectionCrc === undefined) fail("no data section CRC");
else if (crc32(bytes.subarray(0, Number(reader.dataEndOffset))) !== reader.dataSectionCrc) fail("data section CRC mismatch");

// 2. The streaming reader: every record in file order.
const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
stream.append(bytes);
let streamed = 0, record;
while ((record = stream.nextRecord())) if (record.type === "Message") ++streamed;
if (!stream.done()) fail("stream reader: file not read to its end");
if (streamed !== messages.length) fail(`stream reader: ${streamed} messages, indexed reader ${messages.length}`);

// 3. Schemas: every JSON message valid against its channel's schema and the Foxglove one it names.
// Foxglove's and Lichtblick's JSON Schema parser (parseJsonSchema in their mcap-support) reads the properties of
// every "type": "object" in a channel's schema and fails on the channel when one has none: the paths of such objects.
const objectsWithoutProperties = (schema, path = "") =>
  schema === null || typeof schema !== "object" ? []
    : [...(schema.type === "object" && !schema.properties ? [path || "/"] : []),
      ...Object.entries(schema).flatMap(([k, v]) => objectsWithoutProperties(v, `${path}/${k}`))];
const ajv = new Ajv({ strict: false, allErrors: false });
const validators = new Map();
for (const [id, schema] of reader.schemasById) {
  if (schema.encoding !== "jsonschema") { fail(`schema ${schema.name}: encoding ${schema.encoding}`); continue; }
  const own = JSON.parse(new TextDecoder().decode(schema.data));
  const checks = [ajv.compile(own)];
  for (const path of objectsWithoutProperties(own)) fail(`${schema.name}: the object at ${path} has no properties (the viewers cannot parse it)`);
  if (schema.name.startsWith("foxglove.")) {
    const reference = foxgloveSchemas[schema.name.slice("foxglove.".length)];
    if (!reference) fail(`${schema.name}: not in @foxglove/schemas`);
    else {
      if (own.title !== schema.name) fail(`${schema.name}: its schema's title is ${own.title}`);
      checks.push(ajv.compile(reference));
    }
  }
  validators.set(id, checks);
}
// The frame tree: each frame's latest parent, and the frames drawn in since the last change of log time.
const parent = new Map();
const drawnIn = new Set();
let treeTime = -1n, framesChecked = 0;
const rooted = (frame) => {
  for (let f = frame, steps = 0; f !== "map"; f = parent.get(f), ++steps) if (f === undefined || steps > parent.size) return false;
  return true;
};
const checkFrames = () => {
  for (const f of drawnIn) if (!rooted(f)) { fail(`frame ${f} has no path to map at ${treeTime}`); break; }
  framesChecked += drawnIn.size;
  drawnIn.clear();
};
const frames = (schemaName, value) => {
  if (schemaName === "foxglove.FrameTransforms") for (const t of value.transforms) parent.set(t.child_frame_id, t.parent_frame_id);
  else if (schemaName === "foxglove.PoseInFrame") drawnIn.add(value.frame_id);
  else if (schemaName === "foxglove.SceneUpdate") for (const e of value.entities) drawnIn.add(e.frame_id);
};
const key = (e) => `${e.timestamp.toString().padStart(20, "0")} ${JSON.stringify(e.message ?? e.raw)}`;
const textDecoder = new TextDecoder();
const byLcmChannel = new Map();
const validated = new Map();
for (const m of messages) {
  const ch = reader.channelsById.get(m.channelId);
  const entry = { timestamp: m.logTime / 1000n };
  if (ch.messageEncoding === "json") {
    const value = JSON.parse(textDecoder.decode(m.data));
    for (const v of validators.get(ch.schemaId) ?? [])
      if (!v(value)) { fail(`${ch.topic}: ${ajv.errorsText(v.errors)}`); break; }
    validated.set(ch.topic, (validated.get(ch.topic) ?? 0) + 1);
    entry.message = value;
    if (m.logTime !== treeTime) { checkFrames(); treeTime = m.logTime; }
    frames(reader.schemasById.get(ch.schemaId)?.name, value);
  } else if (ch.messageEncoding === "lcm") {
    entry.raw = Buffer.from(m.data).toString("hex");
  } else fail(`${ch.topic}: message encoding ${ch.messageEncoding}`);
  const lcm = ch.metadata.get("lcm_channel");
  if (lcm !== undefined) {
    if (!byLcmChannel.has(lcm)) byLcmChannel.set(lcm, []);
    byLcmChannel.get(lcm).push(entry);
  }
}

checkFrames();
if (framesChecked === 0) fail("no pose or scene entity to check the frames of");
for (const t of required) if (!validated.get(t)) fail(`no message on ${t}`);

// 4. Channel by channel, the LCM log's messages (read line by line: a long run's log is larger than a string can be).
const expected = new Map();
for await (const line of createInterface({ input: createReadStream(jsonlPath), crlfDelay: Infinity })) {
  if (!line) continue;
  const e = JSON.parse(line);
  if (!expected.has(e.channel)) expected.set(e.channel, []);
  expected.get(e.channel).push(key({ timestamp: BigInt(e.timestamp), ...(e.raw ? { raw: e.raw } : { message: e.message }) }));
}
for (const channel of new Set([...expected.keys(), ...byLcmChannel.keys()])) {
  const want = (expected.get(channel) ?? []).sort(), got = (byLcmChannel.get(channel) ?? []).map(key).sort();
  if (want.length !== got.length) { fail(`${channel}: ${want.length} messages in the log, ${got.length} in the MCAP file`); continue; }
  const i = want.findIndex((w, k) => w !== got[k]);
  if (i >= 0) fail(`${channel}: message differs from the log's:\n  log:  ${want[i].slice(0, 300)}\n  mcap: ${got[i].slice(0, 300)}`);
}

const topics = [...validated].map(([t, n]) => `${t} ${n}`).join(", ");
console.log(`${mcapPath}: ${messages.length} messages in ${reader.chunkIndexes.length} chunks; ${expected.size} LCM channels compared; validated: ${topics}`);
if (failures.length) { console.error(`${failures.length} failure(s)`); process.exit(1); }
console.log("check_mcap: ok");
