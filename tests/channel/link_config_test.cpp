#include "channel/link_config.h"

#include <catch2/catch.hpp>
#include <string>

#include "core/json_io.h"
#include "test_support.h"

using uavsim::channel::CheckOutageNodes;
using uavsim::channel::LinkConfig;
using uavsim::channel::Modulation;
using uavsim::core::FromJson;
using uavsim::core::Json;
using uavsim::core::Polarization;
using uavsim::core::ToJson;
using uavsim::testing::ConfigErrorOf;

namespace {

std::string LoadError(const char* text) {
  LinkConfig c;
  return ConfigErrorOf([&] { FromJson(Json::parse(text), "f.json", "/links/default", c); });
}

}  // namespace

TEST_CASE("LinkConfig: new keys read, default and round-trip", "[channel]") {
  LinkConfig c;
  FromJson(Json::parse(R"({
    "fragment_header_bytes": 40, "snr_db": 18.5, "modulation": "64qam", "coding_gain_db": 6,
    "carrier_ghz": 28, "path_length_m": 350, "polarization": "circular",
    "path_elevation_deg": 12,
    "outages": [{"from_s": 1, "to_s": 2}, {"from_s": 3, "to_s": 4, "nodes": ["cam1", "radar1"]}]
  })"),
           "f.json", "/links/default", c);
  CHECK(c.fragment_header_bytes == 40);
  CHECK(c.snr_db == 18.5);
  CHECK(c.modulation == Modulation::kQam64);
  CHECK(c.coding_gain_db == 6.0);
  CHECK(c.carrier_ghz.value() == 28.0);
  CHECK(c.path_length_m == 350.0);
  CHECK(c.polarization == Polarization::kCircular);
  CHECK(c.path_elevation_deg == 12.0);
  REQUIRE(c.outages.size() == 2);
  CHECK(c.outages[0].nodes.empty());
  CHECK(c.outages[1].nodes == std::vector<std::string>{"cam1", "radar1"});
  // Unchanged keys keep their defaults.
  CHECK(c.bandwidth_mbps == 20.0);
  CHECK(c.buffer_packets == 1000);

  LinkConfig back;
  FromJson(ToJson(c), "r.json", "", back);
  CHECK(ToJson(back).dump() == ToJson(c).dump());
  const Json defaults = ToJson(LinkConfig{});
  CHECK(defaults["snr_db"] == 25.0);
  CHECK(defaults["modulation"] == "16qam");
  CHECK(defaults["polarization"] == "horizontal");
  CHECK(defaults["fragment_header_bytes"] == 28);
  CHECK(defaults["carrier_ghz"].is_null());
}

TEST_CASE("LinkConfig: unknown keys and out-of-range values name the pointer", "[channel]") {
  CHECK_THAT(LoadError(R"({"path_lenght_m": 10})"),
             Catch::StartsWith("f.json: /links/default/path_lenght_m: unknown key") &&
                 Catch::Contains("did you mean \"path_length_m\""));
  CHECK_THAT(LoadError(R"({"outages": [{"from_s": 1, "to_s": 2, "node": ["a"]}]})"),
             Catch::StartsWith("f.json: /links/default/outages/0/node: unknown key") &&
                 Catch::Contains("did you mean \"nodes\""));
  CHECK(LoadError(R"({"snr_db": 200})") ==
        "f.json: /links/default/snr_db: expected a number in [-50, 100], got 200");
  CHECK(LoadError(R"({"coding_gain_db": -1})") ==
        "f.json: /links/default/coding_gain_db: expected a number in [0, 20], got -1");
  CHECK(LoadError(R"({"carrier_ghz": 0.5})") ==
        "f.json: /links/default/carrier_ghz: expected a number in [1, 1000], got 0.5");
  CHECK(LoadError(R"({"path_length_m": -5})") ==
        "f.json: /links/default/path_length_m: expected a number in [0, 100000], got -5");
  CHECK(LoadError(R"({"path_elevation_deg": 91})") ==
        "f.json: /links/default/path_elevation_deg: expected a number in [0, 90], got 91");
  CHECK(LoadError(R"({"fragment_header_bytes": 2000})") ==
        "f.json: /links/default/fragment_header_bytes: expected an integer in [0, 1024], got "
        "2000");
  CHECK(LoadError(R"({"mtu_bytes": 64, "fragment_header_bytes": 64})") ==
        "f.json: /links/default/fragment_header_bytes: fragment_header_bytes must be less than "
        "mtu_bytes (64)");
  CHECK(LoadError(R"({"modulation": "8psk"})") ==
        "f.json: /links/default/modulation: expected one of \"bpsk\", \"qpsk\", \"16qam\", "
        "\"64qam\", \"256qam\", got \"8psk\"");
  CHECK(LoadError(R"({"polarization": "diagonal"})") ==
        "f.json: /links/default/polarization: expected one of \"horizontal\", \"vertical\", "
        "\"circular\", got \"diagonal\"");
  CHECK(LoadError(R"({"outages": [{"from_s": 1, "to_s": 2, "nodes": [3]}]})") ==
        "f.json: /links/default/outages/0/nodes/0: expected a string, got 3");
  CHECK(LoadError(R"({"outages": [{"from_s": 1, "to_s": 2, "nodes": ["a", "a"]}]})") ==
        "f.json: /links/default/outages/0/nodes/1: duplicate entry \"a\"");
}

TEST_CASE("LinkConfig: outage nodes must use the link", "[channel]") {
  LinkConfig c;
  FromJson(Json::parse(R"({"outages": [{"from_s": 1, "to_s": 2},
                                       {"from_s": 3, "to_s": 4, "nodes": ["cam1", "cam9"]}]})"),
           "s.json", "/links/default", c);
  CHECK(ConfigErrorOf([&] {
          CheckOutageNodes(c, {"cam1", "lidar1"}, "s.json", "/links/default");
        }) ==
        "s.json: /links/default/outages/1/nodes/1: node \"cam9\" does not use this link "
        "(its nodes: \"cam1\", \"lidar1\")");
  CHECK(ConfigErrorOf([&] { CheckOutageNodes(c, {}, "s.json", "/links/default"); }) ==
        "s.json: /links/default/outages/1/nodes/0: node \"cam1\" does not use this link (no "
        "node uses it)");
  CHECK(ConfigErrorOf([&] {
          CheckOutageNodes(c, {"cam9", "cam1"}, "s.json", "/links/default");
        }).empty());
}
