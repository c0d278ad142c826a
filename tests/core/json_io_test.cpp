#include "core/json_io.h"

#include <catch2/catch.hpp>

#include "test_support.h"

#include "core/weather.h"
#include "sim/scenario.h"

using uavsim::core::ConfigError;
using uavsim::core::Json;
using uavsim::core::ParseJsonText;
using uavsim::core::Rule;

using uavsim::testing::ConfigErrorOf;

TEST_CASE("JsonIo: syntax errors give line and column", "[core]") {
  const std::string e =
      ConfigErrorOf([] { ParseJsonText("{\n  \"a\": 1,\n  \"b\": }\n", "s.json"); });
  CHECK_THAT(e, Catch::StartsWith("s.json: line 3, column 8: invalid JSON"));
}

TEST_CASE("JsonIo: duplicate keys are errors at their pointer", "[core]") {
  CHECK(ConfigErrorOf([] { ParseJsonText(R"({"a": {"b": 1, "b": 2}})", "d.json"); }) ==
        "d.json: /a/b: duplicate key \"b\"");
  CHECK(ConfigErrorOf([] { ParseJsonText(R"({"x": [1, {"k": 1, "k": 2}]})", "d.json"); }) ==
        "d.json: /x/1/k: duplicate key \"k\"");
  // Same key in two different objects is fine.
  CHECK(ConfigErrorOf([] {
          ParseJsonText(R"({"a": {"k": 1}, "b": {"k": 2}, "c": [{"k": 1}, {"k": 2}]})", "d.json");
        }).empty());
}

TEST_CASE("JsonIo: nesting is bounded", "[core]") {
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  CHECK_THAT(ConfigErrorOf([&] { ParseJsonText(deep, "n.json"); }),
             Catch::Contains("nesting deeper than"));
}

TEST_CASE("JsonIo: rules describe themselves", "[core]") {
  CHECK(Rule::Probability().Describe(false) == "a number in [0, 1]");
  CHECK(Rule::Positive().Describe(false) == "a number > 0");
  CHECK(Rule::Range(1, 128).Describe(true) == "an integer in [1, 128]");
  CHECK(Rule::Positive(5).Describe(false) == "a number in (0, 5]");
  CHECK(Rule::Positive(5).Contains(5.0));
  CHECK_FALSE(Rule::Positive(5).Contains(0.0));
}

TEST_CASE("JsonIo: the reader names the pointer, the rule and the value", "[core]") {
  using uavsim::core::WeatherConfig;
  WeatherConfig w;
  auto load = [&](const char* text) {
    return ConfigErrorOf(
        [&] { uavsim::core::FromJson(Json::parse(text), "w.json", "/weather", w); });
  };
  CHECK(load(R"({"rain_mm_h": -1})") ==
        "w.json: /weather/rain_mm_h: expected a number in [0, 300], got -1");
  CHECK(load(R"({"rain_mm_h": "heavy"})") ==
        "w.json: /weather/rain_mm_h: expected a number in [0, 300], got \"heavy\"");
  // A long string is cut on a character's first byte: the line stays UTF-8.
  std::string long_text;
  for (int i = 0; i < 70; ++i) long_text += "\xc3\xa9";  // é
  const std::string cut = load(("{\"rain_mm_h\": \"" + long_text + "\"}").c_str());
  CHECK(cut.find("...\"") != std::string::npos);
  const std::string shown = cut.substr(cut.find("got \"") + 5);
  CHECK(shown.size() % 2 == 0);  // "é" pairs up to the 4 bytes of '..."'
  CHECK(shown.rfind("\xc3\xa9...\"") == shown.size() - 6);
  CHECK(ConfigErrorOf([] { ParseJsonText(R"({"weather": {"rain_mm_h": 1e999}})", "w.json"); }) ==
        "w.json: /weather/rain_mm_h: expected a finite number, got 1e999 (out of range)");
  CHECK(ConfigErrorOf([] { ParseJsonText(R"({"p": [1, 2, -1e400]})", "w.json"); }) ==
        "w.json: /p/2: expected a finite number, got -1e400 (out of range)");
  CHECK(load(R"({"rain_mmh": 3})") ==
        "w.json: /weather/rain_mmh: unknown key (did you mean \"rain_mm_h\"?)");
  CHECK_THAT(load(R"({"zzzzzzzzzz": 3})"), Catch::Contains("unknown key; known keys here:"));
  CHECK(load(R"({"fog_visibility_m": null, "illumination": 0.5})").empty());
  CHECK_FALSE(w.fog_visibility_m.has_value());
  CHECK(w.illumination == 0.5);
  CHECK(load(R"({"fog_visibility_m": 200})").empty());
  REQUIRE(w.fog_visibility_m.has_value());
  CHECK(*w.fog_visibility_m == 200.0);
}

TEST_CASE("JsonIo: a resolved scenario reads back to itself", "[core]") {
  uavsim::sim::Scenario s;
  const Json first = uavsim::sim::ResolvedJson(s);
  const uavsim::sim::Scenario again = uavsim::sim::ScenarioFromJson(first, "r.json", ".");
  CHECK(uavsim::sim::ResolvedJson(again) == first);
  // Every default is written out: the resolved document is complete.
  CHECK(first.contains("links"));
  CHECK(first["nodes"].size() == 3);
  CHECK(first["nodes"][0]["sensor"]["type"] == "fisheye_stereo");
  CHECK(first["weather"]["fog_visibility_m"].is_null());
}

TEST_CASE("JsonIo: error lines show a pointer unambiguously, the document as /", "[core]") {
  using uavsim::core::ShowPointer;
  using uavsim::core::WeatherConfig;
  // Unchanged: the pointers of every earlier error line (issue 43).
  CHECK(ShowPointer("/nodes/1/sensor/rate_hz") == "/nodes/1/sensor/rate_hz");
  CHECK(ShowPointer("/weather/rain~1h") == "/weather/rain~1h");
  CHECK(ShowPointer("/links/") == "/links/");
  CHECK(ShowPointer("line 7, column 3") == "line 7, column 3");
  // A space or a colon would run into the line's ": " separators: quoted,
  // with JSON's escapes; "/" (the key "" at the top) too, apart from the
  // document itself.
  CHECK(ShowPointer("/uavs/0/ name") == "\"/uavs/0/ name\"");
  CHECK(ShowPointer("/a:b") == "\"/a:b\"");
  CHECK(ShowPointer("/a b/\"q\\") == "\"/a b/\\\"q\\\\\"");
  CHECK(ShowPointer("/") == "\"/\"");
  CHECK(std::string(ConfigError("f.json", "/uavs/0/ name", "unknown key").what()) ==
        "f.json: \"/uavs/0/ name\": unknown key");
  const ConfigError root = ConfigError::AboutDocument("f.json", "expected an object, got 42");
  CHECK(std::string(root.what()) == "f.json: /: expected an object, got 42");
  CHECK(root.pointer().empty());
  WeatherConfig w;
  CHECK(ConfigErrorOf([&] {
          uavsim::core::FromJson(Json::parse(R"({" rain_mm_h": 1})"), "w.json", "/weather", w);
        }) == "w.json: \"/weather/ rain_mm_h\": unknown key (did you mean \"rain_mm_h\"?)");
}
