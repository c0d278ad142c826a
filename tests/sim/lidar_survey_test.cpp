// The survey's cache file (sim/lidar_survey.h): what is written reads back
// as the same survey; a file damaged anywhere, cut short or written for
// another key is not used.
#include "sim/lidar_survey.h"

#include <catch2/catch.hpp>
#include <memory>
#include <string>

namespace uavsim::sim {
namespace {

LidarSurvey Example() {
  auto map = std::make_shared<pipeline::LidarPreprocessor::StaticMap>();
  for (std::uint64_t v : {7ull, 3ull, 1ull << 40, 123456789ull}) map->insert(v);
  LidarSurvey s;
  s.map = map;
  s.frames = 42;
  s.coverage = 0.9925;
  return s;
}

TEST_CASE("Survey file: written and read back, the same survey", "[sim]") {
  const std::string key = R"({"node":"lidar1","weather":{}})";
  const std::string bytes = EncodeSurvey(key, Example());
  const auto back = DecodeSurvey(bytes, key);
  REQUIRE(back);
  CHECK(*back->map == *Example().map);
  CHECK(back->frames == 42);
  CHECK(back->coverage == 0.9925);
  // The voxels are written sorted: the bytes do not depend on the set's order.
  auto reordered = std::make_shared<pipeline::LidarPreprocessor::StaticMap>();
  reordered->reserve(100);
  for (std::uint64_t v : {123456789ull, 1ull << 40, 3ull, 7ull}) reordered->insert(v);
  LidarSurvey r = Example();
  r.map = reordered;
  CHECK(EncodeSurvey(key, r) == bytes);
}

TEST_CASE("Survey file: any damaged byte, a cut or another key is refused", "[sim]") {
  const std::string key = R"({"node":"lidar1"})";
  const std::string bytes = EncodeSurvey(key, Example());
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    std::string bad = bytes;
    bad[i] = static_cast<char>(bad[i] ^ 0x01);
    INFO("byte " << i);
    CHECK_FALSE(DecodeSurvey(bad, key));
  }
  for (std::size_t n = 0; n < bytes.size(); ++n) CHECK_FALSE(DecodeSurvey(bytes.substr(0, n), key));
  CHECK_FALSE(DecodeSurvey(bytes + "x", key));
  CHECK_FALSE(DecodeSurvey(bytes, R"({"node":"lidar2"})"));
  CHECK_FALSE(DecodeSurvey(EncodeSurvey(R"({"node":"lidar2"})", Example()), key));
}

}  // namespace
}  // namespace uavsim::sim
