// Sensing traces (sim/sensing_trace.h) in-process: what is written reads
// back as it was, and a trace with any one byte changed, anywhere, is
// refused before a byte of it is used, naming the file and its first bad
// record. (Replays through the binary: tests/apps/cli/trace_test.cpp.)
#include "sim/sensing_trace.h"

#include <catch2/catch.hpp>
#include <cstring>
#include <string>
#include <vector>

#include "core/error.h"
#include "sim/scenario.h"
#include "test_support.h"

using uavsim::core::UsageError;
using uavsim::sim::ParseSensingTrace;
using uavsim::sim::TracedFrame;
using uavsim::testing::ReadFile;
using uavsim::testing::TempDir;

namespace {

const std::string kDefault = std::string(UAVSIM_SOURCE_DIR) + "/scenarios/default.json";
const std::string kKey(64, 'a');

uavsim::pipeline::PointObservation Points(int channels, int count, float base) {
  uavsim::pipeline::PointObservation p;
  p.t_s = base;
  p.channels = channels;
  for (int i = 0; i < channels * count; ++i) p.values.push_back(base + 0.5f * i);
  p.sensor_position_w = {base, 2.0, 3.0};
  return p;
}

// One frame of each kind the format holds: a camera observation, a LiDAR
// and a radar observation, one with further observations, one with no
// sight and one with an empty latent.
std::vector<std::pair<std::uint32_t, TracedFrame>> Frames() {
  std::vector<std::pair<std::uint32_t, TracedFrame>> frames;
  TracedFrame camera;
  camera.t = 33'333'333;
  camera.raw_bytes = 614400;
  uavsim::pipeline::CameraObservation c;
  c.t_s = 0.033;
  c.detected = true;
  c.centre_left_px = {320.5f, 240.25f};
  c.side_right_px = 17.0f;
  c.bearing_left_w = {0.0, 1.0, 0.0};
  camera.content.camera = c;
  camera.content.latent = {0.25f, -1.5f, 3.0f};
  frames.emplace_back(0, camera);
  TracedFrame lidar;
  lidar.t = 100'000'000;
  lidar.raw_bytes = 96000;
  lidar.sight = uavsim::sim::TargetSight{true, false};
  lidar.content.points = Points(4, 3, 1.0f);
  frames.emplace_back(1, lidar);
  TracedFrame radar;
  radar.t = 66'666'667;
  radar.raw_bytes = 131072;
  radar.sight = uavsim::sim::TargetSight{true, true};
  radar.content.points = Points(5, 2, 7.0f);
  radar.content.latent = {1.0f, 2.0f};
  uavsim::sim::NodeObservation further;
  further.points = Points(5, 1, 9.0f);
  further.latent = {4.0f};
  radar.content.further = {further, further};
  frames.emplace_back(2, radar);
  return frames;
}

// The bytes of a trace of Frames() by the default scenario's nodes.
std::string TraceBytes(const uavsim::sim::Scenario& s, const std::string& dir) {
  uavsim::sim::SensingTraceWriter writer(kKey, s);
  for (const auto& [node, frame] : Frames()) writer.Add(node, frame);
  writer.Write(dir);
  return ReadFile(uavsim::sim::SensingTracePath(dir, kKey));
}

std::vector<std::string> NodeIds(const uavsim::sim::Scenario& s) {
  std::vector<std::string> ids;
  for (const auto& n : s.nodes) ids.push_back(n.id);
  return ids;
}

// The message ParseSensingTrace refuses `bytes` with ("" if it reads them).
std::string Refusal(const std::string& bytes, const std::vector<std::string>& ids) {
  try {
    ParseSensingTrace(bytes, "T.trace", kKey, ids);
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("Sensing trace: frames read back as written, in each node's send order", "[sim]") {
  const auto s = uavsim::sim::LoadScenario(kDefault);
  REQUIRE(s.nodes.size() == 3);
  const std::string bytes = TraceBytes(s, TempDir("trace-roundtrip"));
  const auto frames = ParseSensingTrace(bytes, "T.trace", kKey, NodeIds(s));
  REQUIRE(frames.size() == 3);
  for (const auto& [node, frame] : Frames()) {
    INFO("node " << node);
    REQUIRE(frames[node].size() == 1);
    const TracedFrame& f = frames[node].front();
    CHECK(f.t == frame.t);
    CHECK(f.raw_bytes == frame.raw_bytes);
    CHECK(f.sight.has_value() == frame.sight.has_value());
    if (f.sight) CHECK(f.sight->sent_holds == frame.sight->sent_holds);
    CHECK(f.content.latent == frame.content.latent);
    CHECK(f.content.camera.has_value() == frame.content.camera.has_value());
    if (f.content.camera) {
      CHECK(f.content.camera->centre_left_px == frame.content.camera->centre_left_px);
      CHECK(f.content.camera->bearing_left_w == frame.content.camera->bearing_left_w);
      CHECK(f.content.camera->side_right_px == frame.content.camera->side_right_px);
    } else {
      CHECK(f.content.points->values == frame.content.points->values);
      CHECK(f.content.points->channels == frame.content.points->channels);
    }
    REQUIRE(f.content.further.size() == frame.content.further.size());
    for (std::size_t i = 0; i < f.content.further.size(); ++i)
      CHECK(f.content.further[i].points->values == frame.content.further[i].points->values);
  }
  // The last 64 bytes are the SHA-256 of the rest, as sha256sum prints it
  // (checked against OpenSSL's digest of the same bytes by core's tests).
  CHECK(bytes.substr(bytes.size() - 64).find_first_not_of("0123456789abcdef") == std::string::npos);
}

TEST_CASE("Sensing trace: one byte changed anywhere is refused, naming the first bad record",
          "[sim]") {
  const auto s = uavsim::sim::LoadScenario(kDefault);
  const std::string bytes = TraceBytes(s, TempDir("trace-flips"));
  const auto ids = NodeIds(s);
  REQUIRE(Refusal(bytes, ids).empty());
  // The records' starts, from the format (sim/sensing_trace.h): the header
  // after magic and version, three frames, the end record, the digest.
  std::vector<std::size_t> starts = {0};
  std::size_t at = 16;
  for (int record = 0; record < 5; ++record) {
    std::uint32_t size = 0;
    std::memcpy(&size, bytes.data() + at, 4);
    at += 4 + size + 4;
    starts.push_back(at);
    at += 1;  // the next record's tag
  }
  REQUIRE(starts.back() + 64 == bytes.size());
  std::size_t refused = 0;
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    for (const unsigned char flip : {0x01, 0x80, 0xff}) {
      std::string bad = bytes;
      bad[i] = static_cast<char>(bad[i] ^ flip);
      const std::string why = Refusal(bad, ids);
      INFO("byte " << i << " xor " << int(flip) << ": " << why);
      REQUIRE_FALSE(why.empty());
      CHECK(why.rfind("T.trace: ", 0) == 0);
      ++refused;
      if (i < 12) {
        CHECK_THAT(why, Catch::Contains("not a uavsim sensing trace"));
      } else if (i < 16) {
        CHECK_THAT(why, Catch::Contains("format version"));
      } else if (i < starts.back()) {
        // Inside a record: that record is named (a changed tag or size
        // may also read as cut short there).
        std::size_t record = 0;
        while (i >= starts[record + 1]) ++record;
        const std::string name = record == 0 ? "the header" : "record " + std::to_string(record);
        CHECK_THAT(why, Catch::Contains(name + " (byte " + std::to_string(starts[record]) + ")"));
      } else {
        CHECK_THAT(why, Catch::Contains("SHA-256 digest does not match"));
      }
    }
  }
  CHECK(refused == 3 * bytes.size());
  // Cut short anywhere, or with bytes added: refused too.
  for (std::size_t n = 0; n < bytes.size(); n += 7)
    CHECK_FALSE(Refusal(bytes.substr(0, n), ids).empty());
  CHECK_FALSE(Refusal(bytes + "0", ids).empty());
  // Another key or node list, named as such.
  CHECK_THAT(Refusal(bytes, {"cam1", "lidar1"}), Catch::Contains("other nodes"));
  try {
    ParseSensingTrace(bytes, "T.trace", std::string(64, 'b'), ids);
    FAIL("another key read");
  } catch (const UsageError& e) {
    CHECK_THAT(e.what(), Catch::Contains("another sensing key"));
  }
}
