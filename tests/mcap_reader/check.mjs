// Reads a run directory's recording.mcap with the reference TypeScript MCAP
// reader (@mcap/core) and checks it against the MCAP specification, the
// Foxglove schemas (@foxglove/schemas) and the run's own tables:
//
//   node check.mjs RUN_DIR [--dump DIR]
//
// - every record, streamed from the first byte with the chunks' CRCs checked
//   (McapStreamReader, validateCrcs), the Data End CRC recomputed here over
//   the data section (node's zlib.crc32), and read again through the index
//   (McapIndexedReader: footer, summary CRC, summary offsets, chunk indexes,
//   message indexes);
// - the Statistics record's counts against the messages and chunks streamed;
// - each foxglove.* schema in the file equal to the package's (descriptions
//   aside) and every message valid under the package's schema (ajv), the
//   uavsim.* ones under the file's own;
// - the message counts against metrics.json and packets.csv: two images per
//   camera frame, a cloud per LiDAR frame, a cloud and a range-Doppler image
//   per radar frame, the truth and the error per window, each method's
//   estimates per window it estimated, a line per uplink message (fields as
//   packets.csv has them);
// - each image a PNG of the size its calibration says.
// With --dump DIR, the first left eye, the first range-Doppler map and the
// last /window_error message go to DIR for a person to look at.
// Prints "mcap-check: ..." and exits 0 when everything holds, else prints
// each failure and exits 1.
import { createRequire } from "node:module";
import fs from "node:fs";
import path from "node:path";
import zlib from "node:zlib";

const require = createRequire(import.meta.url);
const { McapStreamReader, McapIndexedReader } = require("@mcap/core");
const foxglove = require("@foxglove/schemas/jsonschema");
const zstd = require("@foxglove/wasm-zstd");
const Ajv = require("ajv");

const failures = [];
function check(ok, what) {
  if (!ok) failures.push(what);
  return ok;
}

const args = process.argv.slice(2);
const runDir = args[0];
const dumpDir = args.indexOf("--dump") >= 0 ? args[args.indexOf("--dump") + 1] : null;
const bytes = new Uint8Array(fs.readFileSync(path.join(runDir, "recording.mcap")));
const metrics = JSON.parse(fs.readFileSync(path.join(runDir, "metrics.json"), "utf8"));
const packets = fs.readFileSync(path.join(runDir, "packets.csv"), "utf8").trim().split("\n");

await zstd.isLoaded;
const decompressHandlers = { zstd: (buffer, size) => zstd.decompress(buffer, Number(size)) };

// 1. Every record, in file order.
function streamRecords() {
  const reader = new McapStreamReader({ includeChunks: true, decompressHandlers, validateCrcs: true });
  reader.append(bytes);
  const records = [];
  for (let r; (r = reader.nextRecord()); ) records.push(r);
  check(reader.done(), "the stream reader did not reach the trailing magic");
  return records;
}
const records = streamRecords();
const byType = {};
for (const r of records) byType[r.type] = (byType[r.type] ?? 0) + 1;
const messages = records.filter((r) => r.type === "Message");
const schemas = new Map(records.filter((r) => r.type === "Schema").map((s) => [s.id, s]));
const channels = new Map(records.filter((r) => r.type === "Channel").map((c) => [c.id, c]));
check(records[0]?.type === "Header", "the first record is not the Header");
check(records.at(-1)?.type === "Footer", "the last record is not the Footer");

// The data section's CRC: every byte before the Data End record.
const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
const footerAt = bytes.length - 8 - 29;  // the Footer: opcode, length, 8 + 8 + 4 bytes
const summaryStart = Number(view.getBigUint64(footerAt + 9, true));
const dataEndAt = summaryStart - 13;
const dataEnd = records.find((r) => r.type === "DataEnd");
check(bytes[dataEndAt] === 0x0f, `no Data End record just before the summary (at ${dataEndAt})`);
check(
  dataEnd && dataEnd.dataSectionCrc === zlib.crc32(bytes.subarray(0, dataEndAt)),
  "the Data End CRC is not the CRC of the data section",
);

// 2. Through the index: summary, chunk indexes, message indexes.
const readable = {
  size: async () => BigInt(bytes.length),
  read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
};
const indexed = await McapIndexedReader.Initialize({ readable, decompressHandlers });
const stats = indexed.statistics;
const streamedCounts = new Map();
for (const m of messages) streamedCounts.set(m.channelId, (streamedCounts.get(m.channelId) ?? 0) + 1);
check(stats && Number(stats.messageCount) === messages.length, "Statistics: message_count");
check(Number(stats.chunkCount) === (byType.Chunk ?? 0), "Statistics: chunk_count");
check(stats.channelCount === channels.size && stats.schemaCount === schemas.size,
  "Statistics: channel and schema counts");
check(indexed.chunkIndexes.length === (byType.Chunk ?? 0), "a Chunk Index per chunk");
for (const [id, n] of stats.channelMessageCounts)
  check(Number(n) === (streamedCounts.get(id) ?? 0), `Statistics: messages of channel ${id}`);
let indexedCount = 0, last = -1n;
for await (const m of indexed.readMessages({ validateCrcs: true })) {
  check(m.logTime >= last, "indexed messages out of log-time order");
  last = m.logTime;
  ++indexedCount;
}
check(indexedCount === messages.length, `the index reaches ${indexedCount} of ${messages.length} messages`);

// 3. Schemas: the file's against the package's; every message validated.
const ajv = new Ajv({ strict: false, allErrors: true });
const strip = (o) =>
  Array.isArray(o) ? o.map(strip)
  : o && typeof o === "object"
    ? Object.fromEntries(Object.entries(o).filter(([k]) => k !== "description" && k !== "$comment")
        .map(([k, v]) => [k, strip(v)]))
    : o;
const canonical = (o) => JSON.stringify(o, (_, v) =>
  v && typeof v === "object" && !Array.isArray(v)
    ? Object.fromEntries(Object.keys(v).sort().map((k) => [k, v[k]])) : v);
const validators = new Map();
for (const [id, s] of schemas) {
  check(s.encoding === "jsonschema", `schema ${s.name}: encoding ${s.encoding}`);
  const ours = JSON.parse(new TextDecoder().decode(s.data));
  let reference = ours;
  if (s.name.startsWith("foxglove.")) {
    reference = foxglove[s.name.slice("foxglove.".length)];
    if (!check(reference, `schema ${s.name}: not in @foxglove/schemas`)) continue;
    check(canonical(strip(ours)) === canonical(strip(reference)),
      `schema ${s.name}: differs from @foxglove/schemas' (descriptions aside)`);
  }
  validators.set(id, ajv.compile(reference));
}
const decoded = new Map();  // topic -> messages
for (const m of messages) {
  const channel = channels.get(m.channelId);
  check(channel.messageEncoding === "json", `${channel.topic}: encoding ${channel.messageEncoding}`);
  const value = JSON.parse(new TextDecoder().decode(m.data));
  const validate = validators.get(channel.schemaId);
  if (validate && !validate(value))
    check(false, `${channel.topic} at ${m.logTime}: ${ajv.errorsText(validate.errors)}`);
  if (!decoded.has(channel.topic)) decoded.set(channel.topic, []);
  decoded.get(channel.topic).push(value);
}

// 4. Counts against the run's own tables.
const topicsWhere = (f) => [...channels.values()].filter(f).map((c) => c.topic);
const count = (topics) => topics.reduce((n, t) => n + (decoded.get(t)?.length ?? 0), 0);
const of = (modality, suffix) =>
  topicsWhere((c) => c.metadata.get("modality") === modality && c.topic.endsWith(suffix));
const frames = (m) => metrics.modalities[m]?.frames ?? 0;
const expect = (topics, n, what) =>
  check(count(topics) === n, `${what}: ${count(topics)} messages, the run says ${n}`);
expect(of("camera", "/image"), 2 * frames("camera"), "camera eyes (2 per frame)");
expect(of("lidar", "/points"), frames("lidar"), "LiDAR clouds");
expect(of("radar", "/points"), frames("radar"), "radar clouds");
expect(of("radar", "/range_doppler"), frames("radar"), "range-Doppler maps");
expect(["/truth"], metrics.windows, "truth (per window)");
expect(["/window_error"], metrics.windows, "window errors (per window)");
for (const [method, n] of Object.entries(metrics.estimated_windows))
  expect([`/estimates/${method}`], n, `estimates of ${method}`);
expect(["/uplink"], packets.length - 1, "uplink messages (packets.csv rows)");
expect(["/world"], 1, "the world");
const header = packets[0].split(",");
(decoded.get("/uplink") ?? []).forEach((u, i) => {
  const row = Object.fromEntries(packets[i + 1].split(",").map((v, k) => [header[k], v]));
  check(u.node === row.node && u.status === row.status && String(u.sequence) === row.sequence &&
        String(u.window) === row.window && String(u.bytes) === row.bytes &&
        (row.latency_s === "" ? u.latency_s === null : Math.abs(u.latency_s - row.latency_s) < 1e-6),
    `/uplink message ${i} differs from packets.csv row ${i + 1}`);
});

// 5. Images: PNGs of their calibration's size.
const pngSize = (b) => b.length > 24 && b[0] === 0x89 && b[1] === 0x50
  ? [new DataView(b.buffer, b.byteOffset).getUint32(16), new DataView(b.buffer, b.byteOffset).getUint32(20)] : null;
for (const topic of of("camera", "/image")) {
  const calibration = decoded.get(topic.replace(/\/image$/, "/calibration"))?.[0];
  if (!check(calibration, `${topic}: no calibration`)) continue;
  for (const image of decoded.get(topic) ?? []) {
    const size = pngSize(Buffer.from(image.data, "base64"));
    check(size && size[0] === calibration.width && size[1] === calibration.height,
      `${topic}: an image of ${size} px, the calibration says ${calibration.width} x ${calibration.height}`);
  }
}
for (const topic of [...of("lidar", "/points"), ...of("radar", "/points")])
  for (const cloud of decoded.get(topic) ?? [])
    check(Buffer.from(cloud.data, "base64").length % cloud.point_stride === 0,
      `${topic}: data not a whole number of points`);

if (dumpDir) {
  fs.mkdirSync(dumpDir, { recursive: true });
  const first = (suffix) => decoded.get(topicsWhere((c) => c.topic.endsWith(suffix))[0])?.[0];
  if (first("/left/image")) fs.writeFileSync(path.join(dumpDir, "left.png"), Buffer.from(first("/left/image").data, "base64"));
  if (first("/range_doppler")) fs.writeFileSync(path.join(dumpDir, "range_doppler.png"), Buffer.from(first("/range_doppler").data, "base64"));
  fs.writeFileSync(path.join(dumpDir, "window_error.json"), JSON.stringify(decoded.get("/window_error")?.at(-1), null, 1));
}

for (const [topic, list] of [...decoded.entries()].sort())
  console.log(`mcap-check: ${topic}: ${list.length} messages`);
const summary = `${records.length} records (${byType.Chunk ?? 0} chunks), ${messages.length} messages on ${channels.size} channels`;
if (failures.length) {
  for (const f of failures.slice(0, 50)) console.log(`mcap-check: FAILED: ${f}`);
  console.log(`mcap-check: ${failures.length} failures in ${summary}`);
  process.exit(1);
}
console.log(`mcap-check: OK: ${summary}; every message valid under its Foxglove schema; counts equal the run's`);
