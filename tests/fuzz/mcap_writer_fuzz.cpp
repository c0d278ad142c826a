// libFuzzer target: results/mcap_writer.h's McapWriter. The input is read,
// front to back, as a sequence of writer calls (a short input ends it; every
// value missing reads as 0 or empty):
//   u8 options: bit 0 zstd (else none); bits 1-3 chunk_bytes, one of
//      kChunkBytes; bits 4-7 zstd level minus 5
//   str profile, str library                  (str: u8 length, bytes)
//   then calls, each a u8 whose value mod 8 is
//     0 AddSchema: str name, str encoding, str16 data (u16 length, bytes)
//     1 AddChannel: u16 schema id (any), str topic, str encoding,
//       u8 entries (mod 8) of str key, str value
//     2-5 Write: u8 channel id (0xFF: a u16 follows; unknown ids too),
//       u8 time kind (0 zero, 1 max, 2 the last time, 3/4 the last plus/minus
//       a u16, else a u64 follows), u8 payload kind (0 empty, 1 str16,
//       2 large: u8 fill byte, u24 length up to kMaxLarge, else str)
//     6 once per input: many schemas (even u8) or channels (odd u8), a u16
//       count mod 256
//     7 the writer's statistics() checked against the calls so far
// then Finish() and one Write after it (a std::logic_error). A call the
// writer must refuse (unknown schema or channel id, too many) must throw
// std::invalid_argument and one it must accept must not: anything else is a
// finding. The file is then read by the independent minimal MCAP reader
// below (from the specification, not from the writer): magic at both ends;
// records walk the file exactly; Header; Chunks (zstd decompressed) holding
// exactly the calls' Schema, Channel and Message records in call order, with
// per-channel sequences, their times, sizes and CRC, each closed at the
// first message reaching chunk_bytes; Message Indexes pointing at each
// chunk's messages; Data End's CRC of every byte before it; the summary's
// Schemas, Channels, Chunk Indexes and Statistics, Summary Offsets that
// list them, and the Footer's offsets and CRC. A mismatch aborts.
//
// The writer's id limits (65535 schemas, 65536 channels) are checked once
// at start (LLVMFuzzerInitialize: the same calls, with a bulk op that adds
// up to one past the limit, then a write on the last id). Reaching them
// takes one to two seconds under the sanitizers: as a fuzzed call, which
// libFuzzer's comparison hints find at once, it became most of what the
// fuzzer ran (5 executions a second).
#include <unistd.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <typeinfo>
#include <vector>

#include "core/atomic_file.h"
#include "fuzz_support.h"
#include "results/mcap_writer.h"

namespace {

namespace fs = std::filesystem;
using namespace uavsim;
using fuzz::Finding;

constexpr std::size_t kChunkBytes[] = {
    std::size_t{1} << 20, 0, 1, 64, 1024, 4096, 65536, std::numeric_limits<std::size_t>::max()};
constexpr std::size_t kMaxLarge = std::size_t{2} << 20;  // above the default chunk size
constexpr std::size_t kMaxPayloadTotal = std::size_t{4} << 20;
constexpr std::size_t kMaxSchemas = 65535, kMaxChannels = 65536;
constexpr char kMagic[] = "\x89MCAP0\r\n";
constexpr std::size_t kMagicBytes = 8;

enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

// ---- The input, front to back.

class Input {
 public:
  Input(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool Empty() const { return at_ >= size_; }
  std::uint64_t Le(int bytes) {
    std::uint64_t v = 0;
    for (int i = 0; i < bytes && at_ < size_; ++i) v |= std::uint64_t{data_[at_++]} << (8 * i);
    return v;
  }
  std::uint8_t U8() { return static_cast<std::uint8_t>(Le(1)); }
  std::uint16_t U16() { return static_cast<std::uint16_t>(Le(2)); }
  std::string Bytes(std::size_t n) {
    n = std::min(n, size_ - std::min(at_, size_));
    std::string s(reinterpret_cast<const char*>(data_) + at_, n);
    at_ += n;
    return s;
  }
  std::string Str() { return Bytes(U8()); }
  std::string Str16() { return Bytes(U16()); }

 private:
  const std::uint8_t* data_;
  std::size_t size_, at_ = 0;
};

// ---- The calls the writer accepted: what the file must hold.

struct Schema {
  std::string name, encoding, data;
};
struct Channel {
  std::uint16_t schema = 0;
  std::string topic, encoding;
  std::map<std::string, std::string> metadata;
};
struct Message {
  std::uint16_t channel = 0;
  std::uint64_t time = 0;
  std::string data;
};
// One accepted call: its record's opcode and index in its list.
struct Call {
  std::uint8_t opcode;
  std::size_t index;
};

struct Expected {
  results::McapOptions options;
  std::vector<Schema> schemas;
  std::vector<Channel> channels;
  std::vector<Message> messages;
  std::vector<Call> calls;
  results::McapStatistics stats;  // what statistics() must say, kept as calls are accepted
};

// Runs `call`, which the writer must refuse with std::invalid_argument
// exactly when `refused`. Returns whether it was accepted.
template <class F>
bool Expect(bool refused, const char* what, F&& call) {
  try {
    call();
  } catch (const std::invalid_argument& e) {
    if (!refused) Finding("refused a valid call", std::string(what) + ": " + e.what());
    return false;
  } catch (const std::exception& e) {
    Finding(typeid(e).name(), std::string(what) + ": " + e.what());
  }
  if (refused) Finding("accepted a call it must refuse", what);
  return true;
}

void AddSchema(results::McapWriter& w, Expected& x, Schema s) {
  if (Expect(x.schemas.size() >= kMaxSchemas, "AddSchema", [&] {
        const std::uint16_t id = w.AddSchema(s.name, s.encoding, s.data);
        if (id != x.schemas.size() + 1) Finding("schema id out of order", std::to_string(id));
      })) {
    x.calls.push_back({kSchema, x.schemas.size()});
    x.schemas.push_back(std::move(s));
    x.stats.schema_count = static_cast<std::uint16_t>(x.schemas.size());
  }
}

void AddChannel(results::McapWriter& w, Expected& x, Channel c) {
  const bool refused = c.schema > x.schemas.size() || x.channels.size() >= kMaxChannels;
  if (Expect(refused, "AddChannel", [&] {
        const std::uint16_t id = w.AddChannel(c.schema, c.topic, c.encoding, c.metadata);
        if (id != x.channels.size()) Finding("channel id out of order", std::to_string(id));
      })) {
    x.stats.channel_message_counts[static_cast<std::uint16_t>(x.channels.size())] = 0;
    x.calls.push_back({kChannel, x.channels.size()});
    x.channels.push_back(std::move(c));
    x.stats.channel_count = static_cast<std::uint32_t>(x.channels.size());
  }
}

void Write(results::McapWriter& w, Expected& x, Message m) {
  if (Expect(m.channel >= x.channels.size(), "Write",
             [&] { w.Write(m.channel, m.time, m.data); })) {
    results::McapStatistics& s = x.stats;
    s.message_start_time = s.message_count ? std::min(s.message_start_time, m.time) : m.time;
    s.message_end_time = s.message_count ? std::max(s.message_end_time, m.time) : m.time;
    ++s.message_count;
    ++s.channel_message_counts[m.channel];
    x.calls.push_back({kMessage, x.messages.size()});
    x.messages.push_back(std::move(m));
  }
}

// statistics() against the accepted calls; the per-channel counts (65536
// of them past the limit) only when `all`, at Finish.
void CheckStatistics(const results::McapStatistics& got, const Expected& x, bool all) {
  const results::McapStatistics& want = x.stats;
  if (got.message_count != want.message_count || got.schema_count != want.schema_count ||
      got.channel_count != want.channel_count ||
      got.message_start_time != want.message_start_time ||
      got.message_end_time != want.message_end_time ||
      got.channel_message_counts.size() != want.channel_message_counts.size() ||
      (all && got.channel_message_counts != want.channel_message_counts))
    Finding("statistics() differ from the calls", std::to_string(got.message_count) +
                                                      " messages, want " +
                                                      std::to_string(want.message_count));
}

std::uint64_t NextTime(Input& in, std::uint64_t last) {
  switch (in.U8()) {
    case 0:
      return 0;
    case 1:
      return std::numeric_limits<std::uint64_t>::max();
    case 2:
      return last;
    case 3:
      return last + in.U16();
    case 4:
      return last - in.U16();
    default:
      return in.Le(8);
  }
}

std::string Payload(Input& in, std::size_t* total) {
  switch (in.U8()) {
    case 0:
      return {};
    case 1:
      return in.Str16();
    case 2: {
      const char fill = static_cast<char>(in.U8());
      std::size_t n = std::min<std::size_t>(in.Le(3), kMaxLarge);
      n = std::min(n, kMaxPayloadTotal - std::min(*total, kMaxPayloadTotal));
      *total += n;
      return std::string(n, fill);
    }
    default:
      return in.Str();
  }
}

// Many schemas or channels at once: past the writer's id limits.
bool g_to_limits = false;  // a bulk op adds up to one past the limit (CheckLimits)

void Bulk(results::McapWriter& w, Expected& x, Input& in) {
  const bool schemas = in.U8() % 2 == 0;
  const std::uint16_t count = in.U16();
  const std::size_t had = schemas ? x.schemas.size() : x.channels.size();
  const std::size_t limit = (schemas ? kMaxSchemas : kMaxChannels) + 1;
  const std::size_t n = g_to_limits ? limit - std::min(had, limit) : count % 256;
  for (std::size_t i = 0; i < n; ++i) {
    if (schemas)
      AddSchema(w, x, {"s" + std::to_string(i), "jsonschema", ""});
    else
      AddChannel(w, x, {0, "/t" + std::to_string(i), "json", {}});
  }
}

// Decodes the calls and makes them; returns what the file must hold.
Expected RunCalls(const std::string& path, Input& in) {
  Expected x;
  const std::uint8_t o = in.U8();
  x.options.compression = o & 1 ? results::McapCompression::kZstd : results::McapCompression::kNone;
  x.options.chunk_bytes = kChunkBytes[(o >> 1) & 7];
  x.options.zstd_level = (o >> 4) - 5;
  x.options.profile = in.Str();
  x.options.library = in.Str();
  results::McapWriter w(path, x.options);
  std::uint64_t last_time = 0;
  std::size_t payload_total = 0;
  bool bulk_done = false;
  while (!in.Empty()) {
    switch (in.U8() % 8) {
      case 0:
        AddSchema(w, x, {in.Str(), in.Str(), in.Str16()});
        break;
      case 1: {
        Channel c;
        c.schema = in.U16();
        c.topic = in.Str();
        c.encoding = in.Str();
        for (int n = in.U8() % 8; n > 0; --n) {
          std::string key = in.Str();  // before the value (C++17 reads `a[k] = v` right first)
          c.metadata[key] = in.Str();
        }
        AddChannel(w, x, std::move(c));
        break;
      }
      case 6:
        if (!bulk_done) Bulk(w, x, in);
        bulk_done = true;
        break;
      case 7:
        CheckStatistics(w.statistics(), x, false);
        break;
      default: {
        Message m;
        const std::uint8_t c = in.U8();
        m.channel = c == 0xFF ? in.U16() : c;
        m.time = last_time = NextTime(in, last_time);
        m.data = Payload(in, &payload_total);
        Write(w, x, std::move(m));
      }
    }
  }
  w.Finish();
  CheckStatistics(w.statistics(), x, true);
  try {
    w.Write(0, 0, "after Finish");
    Finding("Write after Finish accepted", "");
  } catch (const std::logic_error& e) {
    // std::invalid_argument is a logic_error too: the refusal must be the
    // writer's "used after Finish", not a channel check.
    if (typeid(e) != typeid(std::logic_error)) Finding("Write after Finish", e.what());
  }
  return x;
}

// ---- The independent reader.

class Reader {
 public:
  Reader(std::string_view s, const char* what) : s_(s), what_(what) {}
  std::uint64_t Le(int bytes) {
    Need(bytes);
    std::uint64_t v = 0;
    for (int i = 0; i < bytes; ++i)
      v |= std::uint64_t{static_cast<unsigned char>(s_[at_ + i])} << (8 * i);
    at_ += bytes;
    return v;
  }
  std::uint8_t U8() { return static_cast<std::uint8_t>(Le(1)); }
  std::uint16_t U16() { return static_cast<std::uint16_t>(Le(2)); }
  std::uint32_t U32() { return static_cast<std::uint32_t>(Le(4)); }
  std::uint64_t U64() { return Le(8); }
  std::string_view Bytes(std::uint64_t n) {
    Need(n);
    const std::string_view v = s_.substr(at_, n);
    at_ += n;
    return v;
  }
  std::string Str() { return std::string(Bytes(U32())); }
  std::string_view Rest() { return Bytes(s_.size() - at_); }
  bool AtEnd() const { return at_ == s_.size(); }
  void End() const {
    if (at_ != s_.size()) Finding("MCAP: bytes left over in", what_);
  }

 private:
  void Need(std::uint64_t n) const {
    if (s_.size() - at_ < n) Finding("MCAP: runs past the end of", what_);
  }
  std::string_view s_;
  const char* what_;
  std::size_t at_ = 0;
};

void Require(bool ok, const char* what, const std::string& detail = "") {
  if (!ok) Finding(what, detail);
}

std::uint32_t Crc32(std::string_view bytes) {
  return static_cast<std::uint32_t>(crc32(crc32(0L, Z_NULL, 0),
                                          reinterpret_cast<const Bytef*>(bytes.data()),
                                          static_cast<uInt>(bytes.size())));
}

struct Record {
  std::uint8_t opcode;
  std::size_t at;  // offset of the opcode in what was split
  std::string_view body;
};

// Splits `bytes` into records (opcode, u64 length, body) covering it exactly.
std::vector<Record> Split(std::string_view bytes, const char* what) {
  std::vector<Record> records;
  Reader r(bytes, what);
  std::size_t at = 0;
  while (at < bytes.size()) {
    const std::uint8_t opcode = r.U8();
    const std::uint64_t length = r.U64();
    records.push_back({opcode, at, r.Bytes(length)});
    at += 9 + length;
  }
  return records;
}

std::map<std::string, std::string> StringMap(std::string_view bytes) {
  std::map<std::string, std::string> m;
  Reader r(bytes, "a map<string, string>");
  while (!r.AtEnd()) {
    std::string key = r.Str();
    Require(m.emplace(std::move(key), r.Str()).second, "MCAP: a map with a key twice");
  }
  return m;
}

void CheckSchema(std::string_view body, const Expected& x, std::size_t index) {
  Reader r(body, "a Schema");
  Require(r.U16() == index + 1, "MCAP: Schema id");
  const Schema& s = x.schemas[index];
  Require(r.Str() == s.name && r.Str() == s.encoding && r.Str() == s.data, "MCAP: Schema fields");
  r.End();
}

void CheckChannel(std::string_view body, const Expected& x, std::size_t index) {
  Reader r(body, "a Channel");
  Require(r.U16() == index, "MCAP: Channel id");
  const Channel& c = x.channels[index];
  Require(r.U16() == c.schema && r.Str() == c.topic && r.Str() == c.encoding,
          "MCAP: Channel fields");
  Require(StringMap(r.Bytes(r.U32())) == c.metadata, "MCAP: Channel metadata");
  r.End();
}

// What the reader saw of one chunk.
struct ChunkSeen {
  std::size_t at = 0, length = 0;  // the Chunk record's offset and length
  std::uint64_t start = 0, end = 0, uncompressed = 0, compressed = 0;
  std::string compression;
  bool has_messages = false;
  std::uint64_t first = 0, last = 0;  // its messages' earliest and latest times
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> index;
  std::map<std::uint16_t, std::size_t> index_at;  // Message Index record offsets
  std::size_t index_length = 0;
};

// The state of the walk through the data section.
struct Walk {
  std::size_t call = 0;  // the next expected call
  std::map<std::uint16_t, std::uint32_t> sequences;
  std::vector<ChunkSeen> chunks;
};

std::string Decompress(std::string_view stored, const std::string& compression,
                       std::uint64_t size) {
  if (compression.empty()) return std::string(stored);
  Require(compression == "zstd", "MCAP: unknown chunk compression", compression);
  Require(size <= (std::uint64_t{64} << 20), "MCAP: chunk larger than the input can make");
  std::string out(size, '\0');
  const std::size_t n = ZSTD_decompress(out.data(), out.size(), stored.data(), stored.size());
  Require(!ZSTD_isError(n) && n == size, "MCAP: zstd chunk does not decompress to its size",
          ZSTD_isError(n) ? ZSTD_getErrorName(n) : std::to_string(n));
  return out;
}

// One record inside a chunk: the next accepted call's.
void CheckChunkRecord(const Record& rec, const Expected& x, Walk& w, ChunkSeen& c) {
  Require(w.call < x.calls.size(), "MCAP: more records than calls");
  const Call call = x.calls[w.call++];
  Require(rec.opcode == call.opcode, "MCAP: a record out of call order",
          std::to_string(rec.opcode));
  if (call.opcode == kSchema) return CheckSchema(rec.body, x, call.index);
  if (call.opcode == kChannel) return CheckChannel(rec.body, x, call.index);
  const Message& m = x.messages[call.index];
  Reader r(rec.body, "a Message");
  Require(r.U16() == m.channel, "MCAP: Message channel");
  Require(r.U32() == w.sequences[m.channel]++, "MCAP: Message sequence");
  Require(r.U64() == m.time && r.U64() == m.time, "MCAP: Message times");
  Require(r.Rest() == m.data, "MCAP: Message data");
  c.index[m.channel].emplace_back(m.time, rec.at);
  c.first = c.has_messages ? std::min(c.first, m.time) : m.time;
  c.last = c.has_messages ? std::max(c.last, m.time) : m.time;
  c.has_messages = true;
}

void CheckChunk(const Record& rec, const Expected& x, Walk& w) {
  ChunkSeen c;
  c.at = rec.at;
  c.length = 9 + rec.body.size();
  Reader r(rec.body, "a Chunk");
  c.start = r.U64();
  c.end = r.U64();
  c.uncompressed = r.U64();
  const std::uint32_t crc = r.U32();
  c.compression = r.Str();
  const std::string_view stored = r.Bytes(r.U64());
  r.End();
  c.compressed = stored.size();
  const bool zstd = x.options.compression == results::McapCompression::kZstd;
  Require(c.compression == (zstd ? "zstd" : ""), "MCAP: chunk compression", c.compression);
  const std::string records = Decompress(stored, c.compression, c.uncompressed);
  Require(records.size() == c.uncompressed, "MCAP: chunk size");
  Require(crc == Crc32(records), "MCAP: chunk CRC");
  const std::vector<Record> inner = Split(records, "a chunk's records");
  Require(!inner.empty(), "MCAP: an empty chunk");
  // A chunk closes at the first message that brings its records to
  // chunk_bytes; the last one at Finish.
  for (std::size_t i = 0; i < inner.size(); ++i) {
    CheckChunkRecord(inner[i], x, w, c);
    const std::size_t end = inner[i].at + 9 + inner[i].body.size();
    if (inner[i].opcode == kMessage && i + 1 < inner.size())
      Require(end < x.options.chunk_bytes, "MCAP: a chunk not closed at chunk_bytes");
  }
  Require(c.start == c.first && c.end == c.last, "MCAP: chunk times");
  Require(w.call == x.calls.size() ||
              (inner.back().opcode == kMessage && c.uncompressed >= x.options.chunk_bytes),
          "MCAP: a chunk closed before chunk_bytes", std::to_string(c.uncompressed));
  w.chunks.push_back(std::move(c));
}

void CheckMessageIndex(const Record& rec, Walk& w) {
  Require(!w.chunks.empty(), "MCAP: a Message Index before any chunk");
  ChunkSeen& c = w.chunks.back();
  Reader r(rec.body, "a Message Index");
  const std::uint16_t channel = r.U16();
  Reader entries(r.Bytes(r.U32()), "a Message Index's entries");
  r.End();
  std::vector<std::pair<std::uint64_t, std::uint64_t>> got;
  for (std::size_t i = 0; i < c.index[channel].size(); ++i) {
    const std::uint64_t t = entries.U64();
    got.emplace_back(t, entries.U64());
  }
  entries.End();
  Require(!got.empty() && got == c.index[channel], "MCAP: Message Index entries");
  Require(c.index_at.empty() || c.index_at.rbegin()->first < channel,
          "MCAP: Message Indexes out of channel order");
  c.index_at[channel] = rec.at;
  c.index_length += 9 + rec.body.size();
}

// Walks the data section; returns the index of the Data End record.
std::size_t CheckData(const std::vector<Record>& records, const std::string& file,
                      const Expected& x, Walk& w) {
  Require(!records.empty() && records[0].opcode == kHeader, "MCAP: no Header first");
  Reader h(records[0].body, "the Header");
  Require(h.Str() == x.options.profile && h.Str() == x.options.library, "MCAP: Header fields");
  h.End();
  std::size_t i = 1;
  for (; i < records.size() && records[i].opcode != kDataEnd; ++i) {
    if (records[i].opcode == kChunk)
      CheckChunk(records[i], x, w);
    else if (records[i].opcode == kMessageIndex)
      CheckMessageIndex(records[i], w);
    else
      Finding("MCAP: an unexpected record in the data section", std::to_string(records[i].opcode));
  }
  Require(i < records.size(), "MCAP: no Data End");
  Require(w.call == x.calls.size(), "MCAP: calls missing from the chunks");
  for (const ChunkSeen& c : w.chunks)
    Require(c.index_at.size() == c.index.size(), "MCAP: a channel without its Message Index");
  Reader d(records[i].body, "Data End");
  Require(d.U32() == Crc32(std::string_view(file).substr(0, records[i].at)),
          "MCAP: Data End's CRC");
  d.End();
  return i;
}

void CheckChunkIndex(std::string_view body, const ChunkSeen& c) {
  Reader r(body, "a Chunk Index");
  Require(r.U64() == c.start && r.U64() == c.end, "MCAP: Chunk Index times");
  Require(r.U64() == c.at && r.U64() == c.length, "MCAP: Chunk Index offset and length");
  Reader offsets(r.Bytes(r.U32()), "a Chunk Index's offsets");
  std::map<std::uint16_t, std::size_t> got;
  for (std::size_t n = 0; n < c.index_at.size(); ++n) {
    const std::uint16_t channel = offsets.U16();
    got[channel] = offsets.U64();
  }
  offsets.End();
  Require(got == c.index_at, "MCAP: Chunk Index's message index offsets");
  Require(r.U64() == c.index_length, "MCAP: Chunk Index's message index length");
  Require(r.Str() == c.compression, "MCAP: Chunk Index compression");
  Require(r.U64() == c.compressed && r.U64() == c.uncompressed, "MCAP: Chunk Index sizes");
  r.End();
}

void CheckStatisticsRecord(std::string_view body, const Expected& x, std::size_t chunks) {
  const results::McapStatistics& s = x.stats;
  Reader r(body, "Statistics");
  Require(r.U64() == s.message_count, "MCAP: Statistics message_count",
          std::to_string(s.message_count));
  Require(r.U16() == s.schema_count && r.U32() == s.channel_count, "MCAP: Statistics counts");
  Require(r.U32() == 0 && r.U32() == 0, "MCAP: Statistics attachments, metadata");
  Require(r.U32() == chunks, "MCAP: Statistics chunk_count");
  Require(r.U64() == s.message_start_time && r.U64() == s.message_end_time,
          "MCAP: Statistics times");
  Reader counts(r.Bytes(r.U32()), "Statistics' channel counts");
  r.End();
  for (const auto& [channel, n] : s.channel_message_counts)
    Require(counts.U16() == channel && counts.U64() == n, "MCAP: Statistics channel counts");
  counts.End();
}

// The summary's groups; returns the index of the first Summary Offset.
std::size_t CheckSummaryGroups(const std::vector<Record>& records, std::size_t i, const Expected& x,
                               const Walk& w) {
  std::size_t schema = 0, channel = 0, chunk = 0;
  for (; i < records.size() && records[i].opcode == kSchema; ++i)
    CheckSchema(records[i].body, x, schema++);
  for (; i < records.size() && records[i].opcode == kChannel; ++i)
    CheckChannel(records[i].body, x, channel++);
  for (; i < records.size() && records[i].opcode == kChunkIndex; ++i)
    CheckChunkIndex(records[i].body, w.chunks.at(chunk++));
  Require(schema == x.schemas.size() && channel == x.channels.size() && chunk == w.chunks.size(),
          "MCAP: summary groups incomplete");
  Require(i < records.size() && records[i].opcode == kStatistics, "MCAP: no Statistics");
  CheckStatisticsRecord(records[i].body, x, w.chunks.size());
  return i + 1;
}

// Each Summary Offset names a group: records of one opcode exactly covering
// [start, start + length); every group is listed once.
std::size_t CheckSummaryOffsets(const std::vector<Record>& records, std::size_t i,
                                std::size_t summary_begin) {
  std::map<std::uint8_t, int> listed;
  for (; i < records.size() && records[i].opcode == kSummaryOffset; ++i) {
    Reader r(records[i].body, "a Summary Offset");
    const std::uint8_t opcode = r.U8();
    const std::uint64_t start = r.U64(), length = r.U64();
    r.End();
    std::uint64_t covered = 0;
    bool started = false;
    for (std::size_t k = summary_begin; k < i; ++k) {
      if (records[k].at == start) started = true;
      if (!started || covered == length) continue;
      Require(records[k].opcode == opcode, "MCAP: a Summary Offset's group mixes records");
      covered += 9 + records[k].body.size();
    }
    Require(started && covered == length, "MCAP: a Summary Offset's group bounds");
    ++listed[opcode];
  }
  std::map<std::uint8_t, int> groups;
  for (std::size_t k = summary_begin; k < i; ++k)
    if (records[k].opcode != kSummaryOffset) groups[records[k].opcode] = 1;
  Require(listed == groups, "MCAP: Summary Offsets do not list each group once");
  return i;
}

void CheckFooter(const std::vector<Record>& records, std::size_t footer, std::size_t summary,
                 std::size_t offsets, const std::string& file) {
  Require(footer + 1 == records.size() && records[footer].opcode == kFooter,
          "MCAP: no Footer last");
  Reader r(records[footer].body, "the Footer");
  const std::uint64_t start = r.U64(), offsets_start = r.U64();
  const std::uint32_t crc = r.U32();
  r.End();
  Require(start == records[summary].at && start < file.size(), "MCAP: Footer summary_start");
  Require(offsets_start == (offsets < footer ? records[offsets].at : 0),
          "MCAP: Footer summary_offset_start");
  const std::size_t crc_end = records[footer].at + 1 + 8 + 8 + 8;
  Require(crc == Crc32(std::string_view(file).substr(start, crc_end - start)),
          "MCAP: Footer summary CRC");
}

void CheckFile(const std::string& file, const Expected& x) {
  Require(file.size() >= 2 * kMagicBytes, "MCAP: shorter than two magics");
  Require(file.compare(0, kMagicBytes, kMagic, kMagicBytes) == 0 &&
              file.compare(file.size() - kMagicBytes, kMagicBytes, kMagic, kMagicBytes) == 0,
          "MCAP: magic missing at an end");
  std::vector<Record> records =
      Split(std::string_view(file).substr(kMagicBytes, file.size() - 2 * kMagicBytes), "the file");
  for (Record& r : records) r.at += kMagicBytes;
  Walk w;
  const std::size_t data_end = CheckData(records, file, x, w);
  const std::size_t offsets = CheckSummaryGroups(records, data_end + 1, x, w);
  const std::size_t footer = CheckSummaryOffsets(records, offsets, data_end + 1);
  CheckFooter(records, footer, data_end + 1, offsets, file);
}

const std::string& Path() {
  static const std::string path = [] {
    const char* tmp = std::getenv("TMPDIR");
    return (fs::path(tmp && *tmp ? tmp : "/tmp") /
            ("uavsim-mcap-writer-fuzz-" + std::to_string(::getpid()) + ".mcap"))
        .string();
  }();
  // Removed at exit (registered after `path` is made, so it runs before
  // `path` is destroyed); a crash leaves the file for the post-mortem.
  static const bool removed_at_exit = (std::atexit([] {
                                         std::error_code ec;
                                         fs::remove(Path(), ec);
                                       }),
                                       true);
  (void)removed_at_exit;
  return path;
}

Expected Run(const std::uint8_t* data, std::size_t size) {
  Input in(data, size);
  Expected x = RunCalls(Path(), in);
  CheckFile(core::ReadFileBytes(Path()), x);
  return x;
}

// Past the id limits: schemas, then channels (zstd, chunks of 1024 bytes),
// then a write on id 65535 (a channel's, or refused without channels).
void CheckLimits() {
  g_to_limits = true;
  for (const std::uint8_t kind : {0, 1}) {
    const std::uint8_t calls[] = {0x39, 0, 0, 6, kind, 0, 0, 2, 0xFF, 0xFF, 0xFF, 1, 3, 1, 'x'};
    const Expected x = Run(calls, sizeof calls);
    const bool full = kind ? x.channels.size() == kMaxChannels && x.messages.size() == 1
                           : x.schemas.size() == kMaxSchemas && x.messages.empty();
    if (!full) Finding("the limits check did not reach the limits", std::to_string(kind));
  }
  g_to_limits = false;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  CheckLimits();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Run(data, size);
  return 0;
}
