#include "results/mcap_writer.h"

#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <stdexcept>
#include <tuple>

namespace uavsim::results {
namespace {

// The specification's opcodes.
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

constexpr char kMagic[] = "\x89MCAP0\r\n";
constexpr std::size_t kMagicBytes = 8;
constexpr std::size_t kRecordPrefixBytes = 9;  // opcode and uint64 length

// Little-endian fields, as the specification's "Serialization" section has them.
void PutLe(std::string& out, std::uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xFF));
}
void U8(std::string& out, std::uint8_t v) { PutLe(out, v, 1); }
void U16(std::string& out, std::uint16_t v) { PutLe(out, v, 2); }
void U32(std::string& out, std::uint32_t v) { PutLe(out, v, 4); }
void U64(std::string& out, std::uint64_t v) { PutLe(out, v, 8); }
// String and uint32-length-prefixed Bytes.
void Str(std::string& out, std::string_view s) {
  if (s.size() > UINT32_MAX) throw std::invalid_argument("MCAP: a string longer than 4 GiB");
  U32(out, static_cast<std::uint32_t>(s.size()));
  out.append(s.data(), s.size());
}

std::string Record(std::uint8_t opcode, const std::string& content) {
  std::string r;
  r.reserve(kRecordPrefixBytes + content.size());
  U8(r, opcode);
  U64(r, content.size());
  r += content;
  return r;
}

unsigned long Crc32(unsigned long crc, const std::string& bytes) {
  // zlib's crc32 takes at most 4 GiB a call; chunks stay far below.
  return crc32(crc, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size()));
}

std::string Zstd(const std::string& in, int level) {
  std::string out(ZSTD_compressBound(in.size()), '\0');
  const std::size_t n = ZSTD_compress(out.data(), out.size(), in.data(), in.size(), level);
  if (ZSTD_isError(n)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
  out.resize(n);
  return out;
}

}  // namespace

McapWriter::McapWriter(const std::string& path, McapOptions options)
    : path_(path), options_(std::move(options)), file_(path, std::ios::binary | std::ios::trunc) {
  if (!file_) throw std::runtime_error(path_ + ": cannot create the MCAP file");
  // The data section's CRC covers the leading magic too (as the reference
  // writers compute it).
  const std::string magic(kMagic, kMagicBytes);
  data_crc_ = Crc32(crc32(0L, Z_NULL, 0), magic);
  WriteRaw(magic);
  std::string header;
  Str(header, options_.profile);
  Str(header, options_.library);
  WriteRecord(kHeader, header);
}

void McapWriter::RequireOpen() const {
  if (finished_) throw std::logic_error(path_ + ": MCAP writer used after Finish");
}

void McapWriter::WriteRaw(const std::string& bytes) {
  file_.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!file_) throw std::runtime_error(path_ + ": cannot write (disk full?)");
  position_ += bytes.size();
}

void McapWriter::WriteRecord(std::uint8_t opcode, const std::string& content) {
  const std::string r = Record(opcode, content);
  data_crc_ = Crc32(data_crc_, r);
  WriteRaw(r);
}

void McapWriter::AddToChunk(std::uint8_t opcode, const std::string& content) {
  U8(chunk_, opcode);
  U64(chunk_, content.size());
  chunk_ += content;
}

std::uint16_t McapWriter::AddSchema(const std::string& name, const std::string& encoding,
                                    const std::string& data) {
  RequireOpen();
  if (schema_records_.size() >= UINT16_MAX) throw std::invalid_argument("MCAP: too many schemas");
  const auto id = static_cast<std::uint16_t>(schema_records_.size() + 1);  // 0 means none
  std::string s;
  U16(s, id);
  Str(s, name);
  Str(s, encoding);
  Str(s, data);
  AddToChunk(kSchema, s);
  schema_records_.push_back(std::move(s));
  stats_.schema_count = id;
  return id;
}

std::uint16_t McapWriter::AddChannel(std::uint16_t schema_id, const std::string& topic,
                                     const std::string& message_encoding,
                                     const std::map<std::string, std::string>& metadata) {
  RequireOpen();
  if (schema_id > schema_records_.size())
    throw std::invalid_argument("MCAP: channel " + topic + " names an unknown schema");
  if (channel_records_.size() > UINT16_MAX) throw std::invalid_argument("MCAP: too many channels");
  const auto id = static_cast<std::uint16_t>(channel_records_.size());
  std::string c;
  U16(c, id);
  U16(c, schema_id);
  Str(c, topic);
  Str(c, message_encoding);
  std::string map;
  for (const auto& [key, value] : metadata) Str(map, key), Str(map, value);
  Str(c, map);  // Map<string, string>: uint32 byte length, then the entries
  AddToChunk(kChannel, c);
  channel_records_.push_back(std::move(c));
  stats_.channel_count = static_cast<std::uint32_t>(channel_records_.size());
  stats_.channel_message_counts[id] = 0;
  return id;
}

void McapWriter::Write(std::uint16_t channel_id, std::uint64_t log_time_ns, std::string_view data) {
  RequireOpen();
  if (channel_id >= channel_records_.size())
    throw std::invalid_argument("MCAP: message on unknown channel " + std::to_string(channel_id));
  chunk_index_[channel_id].emplace_back(log_time_ns, chunk_.size());
  std::string m;
  m.reserve(22 + data.size());
  U16(m, channel_id);
  U32(m, sequences_[channel_id]++);
  U64(m, log_time_ns);  // log_time
  U64(m, log_time_ns);  // publish_time
  m.append(data.data(), data.size());
  AddToChunk(kMessage, m);
  chunk_start_ = chunk_has_messages_ ? std::min(chunk_start_, log_time_ns) : log_time_ns;
  chunk_end_ = chunk_has_messages_ ? std::max(chunk_end_, log_time_ns) : log_time_ns;
  chunk_has_messages_ = true;
  stats_.message_start_time =
      stats_.message_count ? std::min(stats_.message_start_time, log_time_ns) : log_time_ns;
  stats_.message_end_time = std::max(stats_.message_end_time, log_time_ns);
  ++stats_.message_count;
  ++stats_.channel_message_counts[channel_id];
  if (chunk_.size() >= options_.chunk_bytes) CloseChunk();
}

// The Chunk record, then one Message Index record per channel with messages
// in it (in channel id order).
void McapWriter::CloseChunk() {
  if (chunk_.empty()) return;
  const bool zstd = options_.compression == McapCompression::kZstd;
  const std::string records = zstd ? Zstd(chunk_, options_.zstd_level) : std::string();
  const std::string& stored = zstd ? records : chunk_;
  ChunkIndex index{chunk_start_,  chunk_end_, position_,         0, 0, stored.size(),
                   chunk_.size(), {},         zstd ? "zstd" : ""};
  std::string c;
  c.reserve(40 + stored.size());
  U64(c, chunk_start_);
  U64(c, chunk_end_);
  U64(c, chunk_.size());
  U32(c, static_cast<std::uint32_t>(Crc32(crc32(0L, Z_NULL, 0), chunk_)));
  Str(c, index.compression);
  U64(c, stored.size());  // records: uint64-length-prefixed bytes
  c += stored;
  WriteRecord(kChunk, c);
  index.length = position_ - index.offset;
  for (const auto& [channel, entries] : chunk_index_) {
    index.index_offsets[channel] = position_;
    std::string m;
    U16(m, channel);
    U32(m, static_cast<std::uint32_t>(entries.size() * 16));  // Array<Tuple<Timestamp, uint64>>
    for (const auto& [t, offset] : entries) U64(m, t), U64(m, offset);
    WriteRecord(kMessageIndex, m);
  }
  index.index_length = position_ - index.offset - index.length;
  chunks_.push_back(std::move(index));
  ++stats_.chunk_count;
  chunk_.clear();
  chunk_index_.clear();
  chunk_has_messages_ = false;
  chunk_start_ = chunk_end_ = 0;
}

void McapWriter::Finish() {
  RequireOpen();
  CloseChunk();
  std::string data_end;
  U32(data_end, static_cast<std::uint32_t>(data_crc_));
  WriteRaw(Record(kDataEnd, data_end));
  WriteSummary();
  file_.close();
  if (!file_) throw std::runtime_error(path_ + ": cannot close the MCAP file");
  finished_ = true;
}

// Summary groups (Schema, Channel, Chunk Index, Statistics), their Summary
// Offsets, the Footer and the closing magic; the summary's CRC runs from
// its first record through the footer's summary_offset_start.
void McapWriter::WriteSummary() {
  const std::uint64_t summary_start = position_;
  std::string summary;
  std::vector<std::tuple<std::uint8_t, std::uint64_t, std::uint64_t>> groups;
  const auto group = [&](std::uint8_t opcode, const std::vector<std::string>& contents) {
    if (contents.empty()) return;
    const std::uint64_t start = summary_start + summary.size();
    for (const std::string& c : contents) summary += Record(opcode, c);
    groups.emplace_back(opcode, start, summary_start + summary.size() - start);
  };
  group(kSchema, schema_records_);
  group(kChannel, channel_records_);
  std::vector<std::string> chunk_indexes;
  for (const ChunkIndex& c : chunks_) {
    std::string r;
    U64(r, c.start_time), U64(r, c.end_time), U64(r, c.offset), U64(r, c.length);
    std::string offsets;
    for (const auto& [channel, offset] : c.index_offsets)
      U16(offsets, channel), U64(offsets, offset);
    Str(r, offsets);
    U64(r, c.index_length);
    Str(r, c.compression);
    U64(r, c.compressed), U64(r, c.uncompressed);
    chunk_indexes.push_back(std::move(r));
  }
  group(kChunkIndex, chunk_indexes);
  std::string s;
  U64(s, stats_.message_count), U16(s, stats_.schema_count), U32(s, stats_.channel_count);
  U32(s, 0), U32(s, 0);  // attachments, metadata
  U32(s, stats_.chunk_count), U64(s, stats_.message_start_time), U64(s, stats_.message_end_time);
  std::string counts;
  for (const auto& [channel, n] : stats_.channel_message_counts)
    U16(counts, channel), U64(counts, n);
  Str(s, counts);
  group(kStatistics, {s});
  const std::uint64_t offsets_start = summary_start + summary.size();
  for (const auto& [opcode, start, length] : groups) {
    std::string o;
    U8(o, opcode), U64(o, start), U64(o, length);
    summary += Record(kSummaryOffset, o);
  }
  std::string footer;
  U8(footer, kFooter), U64(footer, 20), U64(footer, summary_start), U64(footer, offsets_start);
  const unsigned long crc = Crc32(Crc32(crc32(0L, Z_NULL, 0), summary), footer);
  U32(footer, static_cast<std::uint32_t>(crc));
  WriteRaw(summary);
  WriteRaw(footer);
  WriteRaw(std::string(kMagic, kMagicBytes));
}

}  // namespace uavsim::results
