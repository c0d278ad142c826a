// The MCAP writer against the specification, read back by a small reader of
// the test's own (record framing, offsets, CRCs computed bit by bit here,
// zstd chunks inflated by libzstd). The reference TypeScript reader reads a
// whole run's recording in tests/mcap_reader/.
#include "results/mcap_writer.h"

#include <zstd.h>

#include <catch2/catch.hpp>
#include <cstring>
#include <stdexcept>

#include "test_support.h"

namespace {

using uavsim::results::McapCompression;
using uavsim::results::McapOptions;
using uavsim::results::McapWriter;

// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320), bit by bit.
std::uint32_t Crc32(const std::string& bytes, std::size_t begin, std::size_t end) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (std::size_t i = begin; i < end; ++i) {
    crc ^= static_cast<unsigned char>(bytes[i]);
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

std::uint64_t Le(const std::string& b, std::size_t at, int bytes) {
  REQUIRE(at + bytes <= b.size());
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i)
    v |= std::uint64_t(static_cast<unsigned char>(b[at + i])) << (8 * i);
  return v;
}

struct Rec {
  int opcode;
  std::size_t at;       // of the opcode
  std::string content;  // the record's content
};

// The records of `b` from `at` up to `end`.
std::vector<Rec> Records(const std::string& b, std::size_t at, std::size_t end) {
  std::vector<Rec> out;
  while (at < end) {
    const std::uint64_t n = Le(b, at + 1, 8);
    REQUIRE(at + 9 + n <= end);
    out.push_back({static_cast<unsigned char>(b[at]), at, b.substr(at + 9, n)});
    at += 9 + n;
  }
  return out;
}

// Writes a file of two schemas, three channels and `messages` messages in
// chunks of at most `chunk_bytes`.
std::string WriteSample(const std::string& path, McapCompression compression,
                        std::size_t chunk_bytes, int messages) {
  McapWriter w(path, McapOptions{"", "test", compression, 3, chunk_bytes});
  const auto a = w.AddSchema("a.A", "jsonschema", "{\"type\":\"object\"}");
  const auto b = w.AddSchema("b.B", "jsonschema", "{}");
  const auto c0 = w.AddChannel(a, "/zero", "json", {{"k", "v"}});
  const auto c1 = w.AddChannel(b, "/one", "json");
  const auto c2 = w.AddChannel(a, "/two", "json");
  CHECK(a == 1);
  CHECK(b == 2);
  CHECK((c0 == 0 && c1 == 1 && c2 == 2));
  for (int i = 0; i < messages; ++i)
    w.Write(i % 3 == 2 ? c2
            : i % 2    ? c1
                       : c0,
            1000u * (messages - i) % 7777u, "{\"i\":" + std::to_string(i) + "}");
  w.Finish();
  CHECK(w.statistics().message_count == static_cast<std::uint64_t>(messages));
  return uavsim::testing::ReadFile(path);
}

}  // namespace

TEST_CASE("McapWriter: the test's CRC-32 gives the standard check value", "[results]") {
  CHECK(Crc32("123456789", 0, 9) == 0xCBF43926u);
}

TEST_CASE("McapWriter: magic, header, chunks with their indexes, data end, summary, footer",
          "[results]") {
  const std::string dir = uavsim::testing::TempDir("mcap");
  const std::string b = WriteSample(dir + "/a.mcap", McapCompression::kNone, 200, 20);
  const std::string magic("\x89MCAP0\r\n", 8);
  REQUIRE(b.size() > 16 + 29);
  CHECK(b.substr(0, 8) == magic);
  CHECK(b.substr(b.size() - 8) == magic);
  // The footer: 0x02, length 20, summary_start, summary_offset_start, CRC.
  const std::size_t footer = b.size() - 8 - 29;
  REQUIRE(b[footer] == 0x02);
  CHECK(Le(b, footer + 1, 8) == 20);
  const std::size_t summary = Le(b, footer + 9, 8), offsets = Le(b, footer + 17, 8);
  CHECK(Le(b, footer + 25, 4) == Crc32(b, summary, footer + 25));

  const std::vector<Rec> data = Records(b, 8, summary);
  REQUIRE(data.front().opcode == 0x01);
  REQUIRE(data.back().opcode == 0x0F);
  CHECK(Le(data.back().content, 0, 4) == Crc32(b, 0, data.back().at));
  std::vector<Rec> chunks;
  for (const Rec& r : data) {
    CHECK((r.opcode == 0x01 || r.opcode == 0x06 || r.opcode == 0x07 || r.opcode == 0x0F));
    if (r.opcode == 0x06) chunks.push_back(r);
  }
  CHECK(chunks.size() >= 3);  // 20 messages of ~30 bytes in chunks of 200

  // The summary: schemas, channels, chunk indexes, statistics, then offsets.
  const std::vector<Rec> sum = Records(b, summary, offsets);
  std::vector<int> opcodes;
  for (const Rec& r : sum) opcodes.push_back(r.opcode);
  std::vector<int> expected = {0x03, 0x03, 0x04, 0x04, 0x04};
  expected.insert(expected.end(), chunks.size(), 0x08);
  expected.push_back(0x0B);
  CHECK(opcodes == expected);
  const std::vector<Rec> groups = Records(b, offsets, footer);
  REQUIRE(groups.size() == 4);
  for (const Rec& g : groups) {
    CHECK(g.opcode == 0x0E);
    const std::size_t start = Le(g.content, 1, 8);
    CHECK(static_cast<int>(static_cast<unsigned char>(b[start])) ==
          static_cast<int>(static_cast<unsigned char>(g.content[0])));
    const auto in_group = Records(b, start, start + Le(g.content, 9, 8));
    for (const Rec& r : in_group) CHECK(r.opcode == static_cast<unsigned char>(g.content[0]));
  }
  // Statistics: 20 messages, 2 schemas, 3 channels, 0, 0, the chunks.
  const std::string& stats = sum.back().content;
  CHECK(Le(stats, 0, 8) == 20);
  CHECK(Le(stats, 8, 2) == 2);
  CHECK(Le(stats, 10, 4) == 3);
  CHECK(Le(stats, 22, 4) == chunks.size());
}

TEST_CASE("McapWriter: chunk indexes and message indexes point at their records", "[results]") {
  const std::string dir = uavsim::testing::TempDir("mcap");
  const std::string b = WriteSample(dir + "/a.mcap", McapCompression::kNone, 200, 20);
  const std::size_t footer = b.size() - 8 - 29;
  const std::size_t summary = Le(b, footer + 9, 8), offsets = Le(b, footer + 17, 8);
  std::size_t messages = 0;
  for (const Rec& ci : Records(b, summary, offsets)) {
    if (ci.opcode != 0x08) continue;
    const std::string& c = ci.content;
    const std::size_t at = Le(c, 16, 8), length = Le(c, 24, 8);
    REQUIRE(b[at] == 0x06);
    const Rec chunk = Records(b, at, at + length).front();
    CHECK(chunk.content.size() + 9 == length);
    // Chunk: start, end, uncompressed size, CRC, compression "", records.
    const std::string records = chunk.content.substr(8 + 8 + 8 + 4 + 4 + 8);
    CHECK(Le(chunk.content, 16, 8) == records.size());
    CHECK(Le(chunk.content, 24, 4) == Crc32(records, 0, records.size()));
    CHECK(Le(chunk.content, 32, 8) == records.size());
    const std::size_t map_bytes = Le(c, 32, 4);
    for (std::size_t e = 36; e < 36 + map_bytes; e += 10) {
      const std::uint64_t channel = Le(c, e, 2), index_at = Le(c, e + 2, 8);
      REQUIRE(b[index_at] == 0x07);
      const std::string index =
          Records(b, index_at, index_at + 9 + Le(b, index_at + 1, 8))[0].content;
      CHECK(Le(index, 0, 2) == channel);
      for (std::size_t k = 6; k < index.size(); k += 16) {
        const std::uint64_t t = Le(index, k, 8), offset = Le(index, k + 8, 8);
        REQUIRE(records[offset] == 0x05);
        CHECK(Le(records, offset + 9, 2) == channel);
        CHECK(Le(records, offset + 9 + 6, 8) == t);
        ++messages;
      }
    }
  }
  CHECK(messages == 20);
}

TEST_CASE(
    "McapWriter: zstd chunks inflate to the records an uncompressed writer stores; same calls, "
    "same bytes",
    "[results]") {
  const std::string dir = uavsim::testing::TempDir("mcap");
  const std::string plain = WriteSample(dir + "/plain.mcap", McapCompression::kNone, 1 << 20, 300);
  const std::string z = WriteSample(dir + "/z.mcap", McapCompression::kZstd, 1 << 20, 300);
  CHECK(WriteSample(dir + "/z2.mcap", McapCompression::kZstd, 1 << 20, 300) == z);
  const auto chunk_records = [](const std::string& b) {
    for (const Rec& r : Records(b, 8, b.size() - 8 - 29))
      if (r.opcode == 0x06) return r.content;
    FAIL("no chunk");
    return std::string();
  };
  const std::string pc = chunk_records(plain), zc = chunk_records(z);
  CHECK(Le(zc, 28, 4) == 4);
  CHECK(zc.substr(32, 4) == "zstd");
  const std::string compressed = zc.substr(32 + 4 + 8);
  const std::string expected = pc.substr(8 + 8 + 8 + 4 + 4 + 8);
  std::string inflated(Le(zc, 16, 8), '\0');
  const std::size_t n =
      ZSTD_decompress(inflated.data(), inflated.size(), compressed.data(), compressed.size());
  REQUIRE_FALSE(ZSTD_isError(n));
  CHECK(n == expected.size());
  CHECK(inflated == expected);
  CHECK(Le(zc, 24, 4) == Crc32(expected, 0, expected.size()));
  CHECK(compressed.size() < expected.size() / 2);
}

TEST_CASE("McapWriter: errors name the file; no call after Finish", "[results]") {
  const std::string dir = uavsim::testing::TempDir("mcap");
  try {
    McapWriter w(dir + "/no/such/folder/a.mcap", McapOptions{});
    FAIL("created a file in a missing folder");
  } catch (const std::runtime_error& e) {
    CHECK_THAT(e.what(), Catch::Contains("/no/such/folder/a.mcap: cannot create the MCAP file"));
  }
  McapWriter w(dir + "/a.mcap", McapOptions{});
  CHECK_THROWS_AS(w.Write(0, 0, "x"), std::invalid_argument);             // no channel 0 yet
  CHECK_THROWS_AS(w.AddChannel(1, "/t", "json"), std::invalid_argument);  // no schema 1
  w.Finish();
  CHECK_THROWS_AS(w.AddSchema("s", "jsonschema", "{}"), std::logic_error);
}
