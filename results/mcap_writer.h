// A writer of MCAP files (the MCAP specification, format version 0: magic
// "\x89MCAP0\r\n"), record by record: Header; a data section of Chunks, each
// followed by its Message Index records, then Data End with the CRC32 of
// every byte before it; a summary section of the Schemas, the Channels, one
// Chunk Index per chunk and a Statistics record, each group listed by a
// Summary Offset record; the Footer (with the summary's CRC32) and the magic.
// Schema and Channel records go into the chunk that is open when they are
// added, so a reader that streams the file meets them before their messages.
//
// It knows nothing of what the messages mean: bytes in, bytes out. A chunk
// closes once its uncompressed records reach options.chunk_bytes (or at
// Finish) and is compressed with zstd (libzstd) or stored as it is.
//
// Times are uint64 nanoseconds since whatever epoch the caller uses (the
// simulation clock here). Deterministic: the same calls give the same bytes
// (no wall clock, no addresses; channels indexed in id order).
//
// Errors: every method throws std::runtime_error naming the file when it
// cannot be written, std::invalid_argument for an unknown schema or channel
// id, and std::logic_error for a call after Finish. A writer destroyed
// without Finish leaves a file without summary or footer (readers refuse
// it): callers write into a staging folder that is removed on failure.
#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace uavsim::results {

enum class McapCompression { kNone, kZstd };

struct McapOptions {
  std::string profile;  // the Header's profile ("" : none of the well-known ones)
  std::string library;  // the Header's library: who wrote the file
  McapCompression compression = McapCompression::kZstd;
  int zstd_level = 3;
  std::size_t chunk_bytes = 1 << 20;  // uncompressed records at which a chunk closes
};

// What the Statistics record says (and the writer counted).
struct McapStatistics {
  std::uint64_t message_count = 0;
  std::uint16_t schema_count = 0;
  std::uint32_t channel_count = 0;
  std::uint32_t chunk_count = 0;
  std::uint64_t message_start_time = 0;  // 0 while there are no messages
  std::uint64_t message_end_time = 0;
  std::map<std::uint16_t, std::uint64_t> channel_message_counts;
};

class McapWriter {
 public:
  // Creates (truncates) `path` and writes the magic and the Header.
  McapWriter(const std::string& path, McapOptions options);
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  // A schema (ids 1, 2, ...): `encoding` e.g. "jsonschema", `data` its text.
  std::uint16_t AddSchema(const std::string& name, const std::string& encoding,
                          const std::string& data);
  // A channel (ids 0, 1, ...) on `topic` whose messages follow `schema_id`
  // (0: no schema) in `message_encoding` (e.g. "json").
  std::uint16_t AddChannel(std::uint16_t schema_id, const std::string& topic,
                           const std::string& message_encoding,
                           const std::map<std::string, std::string>& metadata = {});
  // One message; its sequence is the channel's count so far. publish_time =
  // log_time.
  void Write(std::uint16_t channel_id, std::uint64_t log_time_ns, std::string_view data);

  // Closes the last chunk, writes Data End, the summary and the footer, and
  // closes the file.
  void Finish();

  const McapStatistics& statistics() const { return stats_; }
  std::uint64_t bytes_written() const { return position_; }

 private:
  struct ChunkIndex {
    std::uint64_t start_time, end_time, offset, length, index_length, compressed, uncompressed;
    std::map<std::uint16_t, std::uint64_t> index_offsets;
    std::string compression;
  };
  void AddToChunk(std::uint8_t opcode, const std::string& content);
  void CloseChunk();
  void WriteRecord(std::uint8_t opcode, const std::string& content);
  void WriteRaw(const std::string& bytes);
  void WriteSummary();
  void RequireOpen() const;

  std::string path_;
  McapOptions options_;
  std::ofstream file_;
  std::uint64_t position_ = 0;
  unsigned long data_crc_ = 0;  // zlib's crc32 of every byte so far (the data section's)
  bool finished_ = false;

  std::vector<std::string> schema_records_, channel_records_;  // contents, for the summary
  // The open chunk: its records, its messages' times and per channel the
  // (log time, offset in the records) of each message.
  std::string chunk_;
  std::uint64_t chunk_start_ = 0, chunk_end_ = 0;
  bool chunk_has_messages_ = false;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_index_;
  std::vector<ChunkIndex> chunks_;
  std::map<std::uint16_t, std::uint32_t> sequences_;
  McapStatistics stats_;
};

}  // namespace uavsim::results
