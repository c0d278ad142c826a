// `uavsim sweep` (apps/sweep/sweep_spec.h, apps/sweep/sweep.h): the grid, spec errors,
// resuming after a kill, interrupts, mpirun, shards and the report. Points
// are the default scenario cut to 1 s with the EKF only, so they are cheap
// (about a second each).
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <random>
#include <set>
#include <sstream>
#include <thread>

#include "apps/sweep/sweep_spec.h"
#include "core/json_io.h"
#include "test_support.h"

namespace fs = std::filesystem;
using uavsim::core::Json;
using uavsim::testing::Background;
using uavsim::testing::CliResult;
using uavsim::testing::FileList;
using uavsim::testing::FindOnPath;
using uavsim::testing::ReadFile;
using uavsim::testing::RunCli;
using uavsim::testing::RunProgram;
using uavsim::testing::TempDir;
using uavsim::testing::WithoutWallClock;
using uavsim::testing::WriteFile;

namespace {
const std::string kDefault = std::string(UAVSIM_SOURCE_DIR) + "/scenarios/default.json";

// The files every finished point (a whole run directory) holds.
const char* const kPointFiles[] = {"metrics.json", "estimates.csv", "truth.csv", "manifest.json"};

std::size_t CountLines(const std::string& s) {
  return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n'));
}

std::vector<std::string> SplitLines(const std::string& s) {
  std::vector<std::string> lines;
  std::istringstream in(s);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::vector<std::string> SplitCells(const std::string& line) {
  std::vector<std::string> cells;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    cells.push_back(
        line.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) return cells;
    start = comma + 1;
  }
}

// A spec over the default scenario cut to cheap points: 1 s, the EKF only,
// the target where the EKF has a track from the first window on. `rest`
// holds the spec's other members (without braces).
std::string CheapSpec(const std::string& name, const std::string& rest) {
  return R"({"name": ")" + name + R"(", "scenario": ")" + kDefault +
         R"(", "set": {"/duration_s": 1, "/pipeline/methods": ["ekf"],
                       "/uavs/0/trajectory/phase_deg": 90})" +
         (rest.empty() ? "" : ", " + rest) + "}";
}

// The names under DIR/points: finished points, and staging folders.
std::vector<std::string> FinishedPoints(const std::string& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(fs::path(dir) / "points", ec)) {
    const std::string n = e.path().filename().string();
    if (!n.empty() && n[0] != '.') names.push_back(n);
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::vector<std::string> PartialFolders(const std::string& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(fs::path(dir) / "points", ec)) {
    const std::string n = e.path().filename().string();
    if (n.find(".partial-") != std::string::npos) names.push_back(n);
  }
  return names;
}

// Every finished point of DIR is a whole run directory.
void CheckPointsWhole(const std::string& dir) {
  for (const std::string& p : FinishedPoints(dir))
    for (const char* f : kPointFiles) {
      INFO(p << "/" << f);
      CHECK(fs::is_regular_file(fs::path(dir) / "points" / p / f));
    }
}

// Two sweep folders hold the same results: the same files (sweep.json, the
// points' run directories, the tables and plots), equal byte for byte but
// for the wall-clock fields of the points' metrics.json and manifest.json
// and their report.html, which shows those wall times (the sweep's own
// report.html does not, and is compared).
void CheckSameSweep(const std::string& a, const std::string& b) {
  const auto files = FileList(a);
  CHECK(FileList(b) == files);
  for (const std::string& f : files) {
    INFO(f);
    const std::string name = fs::path(f).filename().string();
    if (!fs::exists(fs::path(b) / f)) continue;  // reported above
    if (name == "metrics.json" || name == "manifest.json")
      CHECK(WithoutWallClock(Json::parse(ReadFile(b + "/" + f))) ==
            WithoutWallClock(Json::parse(ReadFile(a + "/" + f))));
    else if (f.rfind("points/", 0) == 0 && name == "report.html")
      CHECK(fs::file_size(fs::path(b) / f) > 0);
    else
      CHECK(ReadFile(b + "/" + f) == ReadFile(a + "/" + f));
  }
}

bool IsPng(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return false;
  return ReadFile(path).rfind("\x89PNG\r\n\x1a\n", 0) == 0;
}

// The uninterrupted local sweep every other way of running is compared
// with: loss p over a range (0.2, 0.3) times seeds 1 and 2, four points,
// --jobs 2. Run once per test process.
struct Reference {
  std::string spec;  // the spec file
  std::string dir;   // its sweep folder
  CliResult result;
  std::string summary, aggregate;
};

const Reference& Ref() {
  static const Reference ref = [] {
    Reference r;
    const std::string root = TempDir("sweep-ref");
    r.spec = root + "/ref.json";
    WriteFile(
        r.spec,
        CheapSpec("ref", R"("parameters": [{"name": "loss", "pointer": "/links/default/loss/p",
                                 "range": {"from": 0.2, "to": 0.3, "step": 0.1}}],
                 "seeds": [1, 2])"));
    r.dir = root + "/out";
    r.result = RunCli({"sweep", r.spec, "--out", r.dir, "--jobs", "2"});
    if (r.result.exit_code == 0) {
      r.summary = ReadFile(r.dir + "/summary.csv");
      r.aggregate = ReadFile(r.dir + "/aggregate.csv");
    }
    return r;
  }();
  INFO("reference sweep: " << ref.result.out << ref.result.err);
  REQUIRE(ref.result.exit_code == 0);
  return ref;
}

}  // namespace

TEST_CASE("Sweep spec: the grid is values x range x cases x seeds, last parameter fastest",
          "[sim][sweep]") {
  const std::string dir = TempDir("sweep-grid");
  const std::string spec = dir + "/grid.json";
  WriteFile(spec, CheapSpec("grid", R"("parameters": [
      {"name": "loss", "pointer": "/links/default/loss/p", "values": [0, 0.25, 0.5]},
      {"name": "rain", "pointer": "/weather/rain_mm_h", "range": {"from": 0, "to": 0.2, "step": 0.1}},
      {"name": "weather", "cases": [
        {"label": "clear", "set": {}},
        {"label": "fog 300 m", "set": {"/weather/fog_visibility_m": 300, "/links/default/snr_db": 10}}]}],
    "seeds": [7, 3])"));
  const uavsim::sim::SweepSpec s = uavsim::sim::LoadSweepSpec(spec);
  CHECK(s.name == "grid");
  REQUIRE(s.parameters.size() == 3);
  CHECK(s.seeds == std::vector<std::uint64_t>{7, 3});
  REQUIRE(s.points.size() == 3u * 3u * 2u * 2u);

  // The labels the tables show: shortest forms, the range without drift.
  const auto tables = s.TableParameters();
  REQUIRE(tables.size() == 3);
  CHECK(tables[0].name == "loss");
  CHECK(tables[0].labels == std::vector<std::string>{"0", "0.25", "0.5"});
  CHECK(tables[1].name == "rain");
  CHECK(tables[1].labels == std::vector<std::string>{"0", "0.1", "0.2"});
  CHECK(tables[2].name == "weather");
  CHECK(tables[2].labels == std::vector<std::string>{"clear", "fog 300 m"});

  const double loss[] = {0, 0.25, 0.5}, rain[] = {0, 0.1, 0.2};
  const std::uint64_t seeds[] = {7, 3};
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    const auto& p = s.points[i];
    INFO("point " << i);
    char id[32];
    std::snprintf(id, sizeof id, "p%04zu", i);
    CHECK(p.id == id);
    const int l = static_cast<int>(i / 12), r = static_cast<int>(i / 4 % 3),
              w = static_cast<int>(i / 2 % 2);
    CHECK(p.value_index == std::vector<int>{l, r, w});
    CHECK(p.seed == seeds[i % 2]);
    // The point's scenario has every assignment applied, and the spec's "set".
    const uavsim::sim::Scenario scenario = s.PointScenario(i);
    CHECK(scenario.seed == seeds[i % 2]);
    CHECK(scenario.duration_s == 1.0);
    CHECK(scenario.pipeline.methods == std::vector<std::string>{"ekf"});
    CHECK(scenario.links.at("default").loss.p == loss[l]);
    CHECK(scenario.weather.rain_mm_h == rain[r]);
    CHECK(scenario.weather.fog_visibility_m.has_value() == (w == 1));
    if (w == 1 && scenario.weather.fog_visibility_m)
      CHECK(*scenario.weather.fog_visibility_m == 300.0);
    CHECK(scenario.links.at("default").snr_db == (w == 1 ? 10.0 : 25.0));
  }

  // Numeric parameters are plot axes, with their values as x.
  std::set<std::string> stems;
  for (const auto& a : s.Axes()) {
    stems.insert(a.stem);
    if (a.stem == "vs_loss") {
      CHECK(a.parameter == 0);
      CHECK(a.x_of_value == std::vector<std::pair<int, double>>{{0, 0}, {1, 0.25}, {2, 0.5}});
    }
    if (a.stem == "vs_rain") {
      CHECK(a.parameter == 1);
      CHECK(a.x_of_value == std::vector<std::pair<int, double>>{{0, 0}, {1, 0.1}, {2, 0.2}});
      CHECK(a.x_label == "rain (mm/h)");  // the key's unit suffix
    }
  }
  CHECK(stems.count("vs_loss") == 1);
  CHECK(stems.count("vs_rain") == 1);
  CHECK(stems.size() == 2);  // the fog case sets two pointers: no curve along either

  // A cases parameter: a curve per pointer over the cases that set only it,
  // and the cases that set nothing at the base value (clear: no rain).
  const std::string cases = dir + "/cases.json";
  WriteFile(cases, CheapSpec("cases", R"("parameters": [
      {"name": "weather", "cases": [
        {"label": "rain 25", "set": {"/weather/rain_mm_h": 25}},
        {"label": "clear", "set": {}},
        {"label": "rain 10", "set": {"/weather/rain_mm_h": 10}},
        {"label": "fog 300 m", "set": {"/weather/fog_visibility_m": 300}},
        {"label": "fog 30 m", "set": {"/weather/fog_visibility_m": 30}}]}])"));
  const auto axes = uavsim::sim::LoadSweepSpec(cases).Axes();
  REQUIRE(axes.size() == 2);
  CHECK(axes[0].stem == "vs_rain_mm_h");
  CHECK(axes[0].x_label == "rain (mm/h)");
  CHECK(axes[0].x_of_value == std::vector<std::pair<int, double>>{{1, 0}, {2, 10}, {0, 25}});
  CHECK_FALSE(axes[0].log_x);  // 0 is on it
  CHECK(axes[1].stem == "vs_fog_visibility_m");
  CHECK(axes[1].x_label == "fog visibility (m)");
  CHECK(axes[1].x_of_value == std::vector<std::pair<int, double>>{{4, 30}, {3, 300}});
  CHECK_FALSE(axes[1].log_x);  // a factor of 10: linear
}

TEST_CASE("Sweep spec: ranges give exact decimal values, seeds from-count, no parameters",
          "[sim][sweep]") {
  const std::string dir = TempDir("sweep-range");
  struct Case {
    const char* range;
    std::vector<std::string> labels;
    std::vector<double> values;
  };
  for (const Case& c : std::vector<Case>{
           {R"({"from": 0, "to": 0.2, "step": 0.1})", {"0", "0.1", "0.2"}, {0, 0.1, 0.2}},
           {R"({"from": 0.1, "to": 0.3, "step": 0.1})", {"0.1", "0.2", "0.3"}, {0.1, 0.2, 0.3}},
           {R"({"from": 0.2, "to": 0.3, "step": 0.1})", {"0.2", "0.3"}, {0.2, 0.3}},
           {R"({"from": 0, "to": 0.25, "step": 0.1})", {"0", "0.1", "0.2"}, {0, 0.1, 0.2}},
           {R"({"from": 0.7, "to": 0.7, "step": 0.1})", {"0.7"}, {0.7}},
           {R"({"from": 0, "to": 1, "step": 0.1})",
            {"0", "0.1", "0.2", "0.3", "0.4", "0.5", "0.6", "0.7", "0.8", "0.9", "1"},
            {0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1}}}) {
    INFO(c.range);
    const std::string spec = dir + "/range.json";
    WriteFile(spec, CheapSpec("range", std::string(R"("parameters": [{"name": "loss",
        "pointer": "/links/default/loss/p", "range": )") +
                                           c.range + "}]"));
    const auto s = uavsim::sim::LoadSweepSpec(spec);
    REQUIRE(s.parameters.size() == 1);
    CHECK(s.TableParameters().at(0).labels == c.labels);
    REQUIRE(s.points.size() == c.values.size());
    for (std::size_t i = 0; i < c.values.size(); ++i)
      CHECK(s.PointScenario(i).links.at("default").loss.p == c.values[i]);
  }

  // Seeds as {from, count}; without parameters, a point per seed.
  WriteFile(dir + "/seeds.json", CheapSpec("seeds", R"("seeds": {"from": 5, "count": 3})"));
  const auto s = uavsim::sim::LoadSweepSpec(dir + "/seeds.json");
  CHECK(s.parameters.empty());
  CHECK(s.seeds == std::vector<std::uint64_t>{5, 6, 7});
  REQUIRE(s.points.size() == 3);
  for (std::size_t i = 0; i < 3; ++i) {
    CHECK(s.points[i].value_index.empty());
    CHECK(s.PointScenario(i).seed == 5 + i);
  }
  // Without "seeds", the base scenario's seed (default.json: 1).
  WriteFile(dir + "/noseeds.json", CheapSpec("noseeds", ""));
  const auto one = uavsim::sim::LoadSweepSpec(dir + "/noseeds.json");
  REQUIRE(one.points.size() == 1);
  CHECK(one.points[0].seed == 1);
  CHECK(one.points[0].id == "p0000");
}

TEST_CASE(
    "Sweep spec errors exit 2 with one line naming the spec and its pointer, creating nothing",
    "[sim][sweep][slow]") {
  const std::string dir = TempDir("sweep-errors");
  const std::string loss = R"("pointer": "/links/default/loss/p")";
  struct Case {
    std::string what;
    std::string spec;     // the whole spec
    std::string pointer;  // the spec pointer the message names (a prefix if it ends with '/')
    std::string also;     // more the message should say ("" for nothing)
  };
  const std::vector<Case> cases{
      {"an unknown scenario pointer",
       CheapSpec("e", R"("parameters": [{"name": "x", "pointer": "/links/default/los/p",
                                         "values": [0.1]}])"),
       "/parameters/0/pointer", "los"},
      {"a pointer through a number",
       CheapSpec("e", R"("parameters": [{"name": "x", "pointer": "/links/default/loss/p/q",
                                         "values": [0.1]}])"),
       "/parameters/0/pointer", "p0000"},
      {"an object value invalid in a part",
       CheapSpec("e", R"("parameters": [{"name": "l", "pointer": "/links/default/loss",
           "values": [{"type": "bernoulli", "p": 0.1}, {"type": "bernoulli", "p": 1.5}]}])"),
       "/parameters/0/values/1", "/links/default/loss/p"},
      {"the same number twice",
       CheapSpec("e", R"("parameters": [{"name": "loss", )" + loss + R"(, "values": [0, 0.0]}])"),
       "/parameters/0/values/1", ""},
      {"a value invalid at one grid point",
       CheapSpec("e", R"("parameters": [{"name": "loss", )" + loss + R"(, "values": [0, 1.5]}])"),
       "/parameters/0/values/1", "p0001"},
      {"a range value invalid at a grid point",
       CheapSpec("e", R"("parameters": [{"name": "loss", )" + loss +
                          R"(, "range": {"from": 0.5, "to": 1.5, "step": 0.5}}])"),
       "/parameters/0/range", "/links/default/loss/p"},
      {"a case setting an invalid value",
       CheapSpec("e", R"("parameters": [{"name": "w", "cases": [{"label": "a", "set": {}},
           {"label": "b", "set": {"/weather/rain_mm_h": -4}}]}])"),
       "/parameters/0/cases/1/set/~1weather~1rain_mm_h", "rain_mm_h"},
      {"a bad set key",
       R"({"scenario": ")" + kDefault + R"(", "set": {"/duration_s": 1, "/bogus": 3}})",
       "/set/~1bogus", "bogus"},
      {"a set key that is not a pointer",
       R"({"scenario": ")" + kDefault + R"(", "set": {"duration_s": 1}})", "/set/duration_s", ""},
      {"a set value invalid in the scenario",
       R"({"scenario": ")" + kDefault + R"(", "set": {"/duration_s": -1}})", "/set/~1duration_s",
       "duration_s"},
      {"an unknown top-level key", CheapSpec("e", R"("parameter": [])"), "/parameter", ""},
      {"values not an array",
       CheapSpec("e", R"("parameters": [{"name": "loss", )" + loss + R"(, "values": 0.1}])"),
       "/parameters/0/values", ""},
      {"an empty values array",
       CheapSpec("e", R"("parameters": [{"name": "loss", )" + loss + R"(, "values": []}])"),
       "/parameters/0/values", ""},
      {"a repeated value",
       CheapSpec("e", R"("parameters": [{"name": "loss", )" + loss + R"(, "values": [0.1, 0.1]}])"),
       "/parameters/0/values/1", ""},
      {"a negative seed", CheapSpec("e", R"("seeds": [1, -1])"), "/seeds/1", ""},
      {"a fractional seed", CheapSpec("e", R"("seeds": [1.5])"), "/seeds/0", ""},
      {"a duplicate seed", CheapSpec("e", R"("seeds": [4, 2, 4])"), "/seeds/2", ""},
      {"seeds from-count with count 0", CheapSpec("e", R"("seeds": {"from": 1, "count": 0})"),
       "/seeds/count", ""},
      {"seeds of the wrong type", CheapSpec("e", R"("seeds": "1,2")"), "/seeds", ""},
      {"a duplicate parameter name",
       CheapSpec("e", R"("parameters": [{"name": "a", )" + loss + R"(, "values": [0.1]},
                                         {"name": "a", "pointer": "/weather/rain_mm_h",
                                          "values": [1]}])"),
       "/parameters/1/name", ""},
      {"a range with step 0",
       CheapSpec("e", R"("parameters": [{"name": "loss", )" + loss +
                          R"(, "range": {"from": 0, "to": 0.2, "step": 0}}])"),
       "/parameters/0/range/step", ""},
      {"a range going down",
       CheapSpec("e", R"("parameters": [{"name": "loss", )" + loss +
                          R"(, "range": {"from": 0.2, "to": 0.1, "step": 0.1}}])"),
       "/parameters/0/range/to", ""},
      {"both values and range",
       CheapSpec("e", R"("parameters": [{"name": "loss", )" + loss +
                          R"(, "values": [0.1], "range": {"from": 0, "to": 0.2, "step": 0.1}}])"),
       "/parameters/0", ""},
      {"a parameter sweeping the seed",
       CheapSpec("e", R"("parameters": [{"name": "s", "pointer": "/seed", "values": [1, 2]}])"),
       "/parameters/0/pointer", "seeds"},
      {"a parameter name that cannot name a file",
       CheapSpec("e", R"("parameters": [{"name": "a/b", )" + loss + R"(, "values": [0.1]}])"),
       "/parameters/0/name", ""},
      {"a repeated case label",
       CheapSpec("e", R"("parameters": [{"name": "w", "cases": [{"label": "a", "set": {}},
                                                                {"label": "a", "set": {}}]}])"),
       "/parameters/0/cases/1/label", ""},
      {"a missing base scenario file", R"({"scenario": "no_such_base.json"})", "/scenario",
       "no_such_base.json"},
      {"no base scenario", R"({"seeds": [1]})", "", "scenario"},
  };
  int n = 0;
  for (const Case& c : cases) {
    INFO(c.what << "\nspec: " << c.spec);
    const std::string spec = dir + "/spec" + std::to_string(n) + ".json";
    const std::string out = dir + "/out" + std::to_string(n++);
    WriteFile(spec, c.spec);
    const CliResult r = RunCli({"sweep", spec, "--out", out, "--quiet"});
    INFO("stderr: " << r.err);
    CHECK(r.exit_code == 2);
    CHECK(CountLines(r.err) == 1);
    CHECK(r.out.empty());
    if (c.pointer.empty())
      CHECK_THAT(r.err, Catch::StartsWith(spec + ": /: missing"));
    else if (c.pointer.back() == '/')
      CHECK_THAT(r.err, Catch::StartsWith(spec + ": " + c.pointer));
    else
      CHECK_THAT(r.err, Catch::StartsWith(spec + ": " + c.pointer + ": "));
    if (!c.also.empty()) CHECK_THAT(r.err, Catch::Contains(c.also));
    CHECK_FALSE(fs::exists(out));
  }
  // The same refusals in-process: a ConfigError naming the spec file.
  const std::string msg =
      uavsim::testing::ConfigErrorOf([&] { uavsim::sim::LoadSweepSpec(dir + "/spec4.json"); });
  CHECK_THAT(msg, Catch::StartsWith(dir + "/spec4.json: /parameters/0/values/1: "));
}

TEST_CASE("Sweep: a full sweep writes summary.csv, aggregate.csv and plots", "[sim][sweep][slow]") {
  const Reference& ref = Ref();
  CHECK(FinishedPoints(ref.dir) == std::vector<std::string>{"p0000", "p0001", "p0002", "p0003"});
  CHECK(PartialFolders(ref.dir).empty());
  CheckPointsWhole(ref.dir);
  CHECK_THAT(ref.result.out, Catch::Contains("4 points: 4 run now, 0 already done, 0 failed"));
  CHECK(ref.result.err.find("warning") == std::string::npos);

  // A row per point in grid order: loss (the range's labels), then the seeds.
  const auto rows = SplitLines(ref.summary);
  REQUIRE(rows.size() == 5);
  const auto header = SplitCells(rows[0]);
  REQUIRE(header.size() > 3);
  CHECK(header[0] == "point");
  CHECK(header[1] == "loss");
  CHECK(header[2] == "seed");
  CHECK(std::find(header.begin(), header.end(), "rmse_ekf") != header.end());
  const char* expected[4][3] = {
      {"p0000", "0.2", "1"}, {"p0001", "0.2", "2"}, {"p0002", "0.3", "1"}, {"p0003", "0.3", "2"}};
  for (int i = 0; i < 4; ++i) {
    const auto cells = SplitCells(rows[i + 1]);
    INFO(rows[i + 1]);
    REQUIRE(cells.size() == header.size());
    for (int k = 0; k < 3; ++k) CHECK(cells[k] == expected[i][k]);
  }
  // A row per setting, over its two seeds.
  const auto agg = SplitLines(ref.aggregate);
  REQUIRE(agg.size() == 3);
  const auto agg_header = SplitCells(agg[0]);
  REQUIRE(agg_header.size() > 2);
  CHECK(agg_header[0] == "loss");
  CHECK(std::find(agg_header.begin(), agg_header.end(), "rmse_ekf_mean") != agg_header.end());
  CHECK(SplitCells(agg[1]).at(0) == "0.2");
  CHECK(SplitCells(agg[2]).at(0) == "0.3");

  // Plots against the numeric parameter, and rate vs SNR per setting.
  for (const char* png :
       {"rmse_vs_loss.png", "delivery_vs_loss.png", "rate_snr_000.png", "rate_snr_001.png"}) {
    INFO(png);
    CHECK(IsPng(ref.dir + "/plots/" + png));
  }
  CHECK(fs::is_regular_file(ref.dir + "/plots/rmse_vs_loss.csv"));

  // report.html, and `uavsim report` redraws it (on a copy: other tests
  // compare the reference's files), referencing only files that exist.
  CHECK(fs::is_regular_file(ref.dir + "/report.html"));
  const std::string copy = TempDir("sweep-report") + "/copy";
  fs::copy(ref.dir, copy, fs::copy_options::recursive);
  fs::remove(copy + "/report.html");
  fs::remove_all(copy + "/plots");
  const CliResult redraw = RunCli({"report", copy, "--quiet"});
  INFO(redraw.err);
  CHECK(redraw.exit_code == 0);
  const auto refs = uavsim::testing::CheckReportReferences(copy);
  CHECK(refs.missing.empty());
  CHECK(refs.small_pngs.empty());
  CHECK(refs.pngs >= 2);  // the loss axis's small multiples and rate vs SNR at least
}

TEST_CASE("Sweep: a killed sweep resumes where it stopped, to the same tables",
          "[sim][sweep][slow]") {
  const Reference& ref = Ref();
  const std::string root = TempDir("sweep-resume");
  const std::string out = root + "/out";
  const std::vector<std::string> args{"sweep", ref.spec, "--out", out, "--jobs", "1", "--quiet"};
  Background sweep(args, root + "/killed");
  // Killed while a later point is under way: p0000 is done, another is staged.
  const bool mid_point = sweep.FreezeWhen(
      [&] { return fs::exists(out + "/points/p0000") && !PartialFolders(out).empty(); });
  kill(-sweep.pid(), SIGKILL);
  const int killed_rc = sweep.Wait();
  INFO("killed sweep said: " << ReadFile(root + "/killed.err"));
  REQUIRE(mid_point);
  CHECK(killed_rc == 128 + SIGKILL);
  const auto before = FinishedPoints(out);
  REQUIRE(!before.empty());
  REQUIRE(before.size() < 4);
  CheckPointsWhole(out);  // nothing half-written under a final name
  CHECK_FALSE(fs::exists(out + "/summary.csv"));
  CHECK_FALSE(fs::exists(out + "/aggregate.csv"));
  CHECK_FALSE(PartialFolders(out).empty());  // what the killed point left

  // The same command again: redoes the killed point, runs the rest.
  const CliResult resumed = RunCli({"sweep", ref.spec, "--out", out, "--jobs", "1"});
  INFO("resumed: " << resumed.out << resumed.err);
  CHECK(resumed.exit_code == 0);
  CHECK_THAT(resumed.out, Catch::Contains(std::to_string(4 - before.size()) + " run now, " +
                                          std::to_string(before.size()) + " already done"));
  CHECK(FinishedPoints(out) == std::vector<std::string>{"p0000", "p0001", "p0002", "p0003"});
  CheckPointsWhole(out);
  CHECK(PartialFolders(out).empty());
  REQUIRE(fs::exists(out + "/summary.csv"));
  CHECK(ReadFile(out + "/summary.csv") == ref.summary);
  CHECK(ReadFile(out + "/aggregate.csv") == ref.aggregate);
  CheckSameSweep(ref.dir, out);

  // Once more: nothing left to run, the same tables.
  const std::string manifest = ReadFile(out + "/points/p0003/manifest.json");
  const CliResult again = RunCli({"sweep", ref.spec, "--out", out});
  INFO("again: " << again.out << again.err);
  CHECK(again.exit_code == 0);
  CHECK_THAT(again.out, Catch::Contains("4 points: 0 run now, 4 already done"));
  CHECK(ReadFile(out + "/points/p0003/manifest.json") == manifest);
  CHECK(ReadFile(out + "/summary.csv") == ref.summary);
}

TEST_CASE("Sweep: killed at random moments, then resumed, it gives the same tables",
          "[sim][sweep][kill][slow]") {
  const Reference& ref = Ref();
  const std::string root = TempDir("sweep-random-kills");
  const std::string out = root + "/out";
  const std::vector<std::string> args{"sweep", ref.spec, "--out", out, "--jobs", "1", "--quiet"};
  // The span of a whole sweep, to place the kills over it (not a measurement).
  const auto start = std::chrono::steady_clock::now();
  REQUIRE(
      RunCli({"sweep", ref.spec, "--out", root + "/whole", "--jobs", "1", "--quiet"}).exit_code ==
      0);
  const double span_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::mt19937_64 rng(24);
  std::uniform_real_distribution<double> moment(0.02, 0.6);
  for (int k = 0; k < 3; ++k) {
    const double at_s = moment(rng) * span_s;
    INFO("kill " << k << " at " << at_s << " s of " << span_s << " s");
    Background sweep(args, root + "/log" + std::to_string(k));
    std::this_thread::sleep_for(std::chrono::duration<double>(at_s));
    kill(-sweep.pid(), SIGKILL);
    sweep.Wait();
    CheckPointsWhole(out);  // nothing half-written under a final name
    if (fs::exists(out + "/summary.csv")) CHECK(ReadFile(out + "/summary.csv") == ref.summary);
  }
  const CliResult resumed = RunCli(args);
  INFO("resumed: " << resumed.out << resumed.err);
  REQUIRE(resumed.exit_code == 0);
  CHECK(PartialFolders(out).empty());
  CHECK(FinishedPoints(out) == std::vector<std::string>{"p0000", "p0001", "p0002", "p0003"});
  CHECK(ReadFile(out + "/summary.csv") == ref.summary);
  CHECK(ReadFile(out + "/aggregate.csv") == ref.aggregate);
}

TEST_CASE("Sweep: SIGINT or SIGTERM stops a sweep with exit 130, keeping finished points",
          "[sim][sweep][slow]") {
  const std::string root = TempDir("sweep-signal");
  const std::string spec = root + "/signal.json";
  WriteFile(spec, CheapSpec("signal", R"("seeds": {"from": 1, "count": 6})"));
  // SIGINT to the whole group (Ctrl-C at a terminal); SIGTERM to the sweep
  // alone (a batch scheduler), which must stop its points itself.
  for (const bool group : {true, false}) {
    const int sig = group ? SIGINT : SIGTERM;
    INFO((group ? "SIGINT to the group" : "SIGTERM to the sweep"));
    const std::string out = root + "/out" + std::to_string(sig);
    const std::string log = root + "/log" + std::to_string(sig);
    Background sweep({"sweep", spec, "--out", out, "--quiet"}, log);
    const pid_t pid = sweep.pid();
    const bool started = sweep.WaitFor(
        [&] { return fs::exists(out + "/points/p0000") && !PartialFolders(out).empty(); });
    kill(group ? -pid : pid, sig);
    const int rc = sweep.Wait();
    INFO("stderr: " << ReadFile(log + ".err"));
    REQUIRE(started);
    CHECK(rc == 130);
    CHECK_THAT(ReadFile(log + ".err"), Catch::Contains("interrupted"));
    // Its points stopped with it: nobody is left in its process group.
    const int alive = kill(-pid, 0);
    const int why = errno;
    CHECK(alive == -1);
    CHECK(why == ESRCH);
    const auto done = FinishedPoints(out);
    CHECK(!done.empty());
    CHECK(done.size() < 6);
    CHECK(std::find(done.begin(), done.end(), "p0000") != done.end());
    CheckPointsWhole(out);
    CHECK(PartialFolders(out).empty());  // interrupted points clean up
    CHECK_FALSE(fs::exists(out + "/summary.csv"));
  }

  // A large grid takes a while to check (about a millisecond a point): a
  // signal then stops the sweep before it creates anything.
  const std::string big = root + "/big.json";
  WriteFile(big, CheapSpec("big", R"("parameters": [
      {"name": "loss", "pointer": "/links/default/loss/p",
       "range": {"from": 0, "to": 0.995, "step": 0.005}},
      {"name": "rain", "pointer": "/weather/rain_mm_h", "range": {"from": 0, "to": 99, "step": 1}}],
      "seeds": [1, 2])"));
  const std::string out = root + "/big-out";
  Background sweep({"sweep", big, "--out", out, "--quiet"}, root + "/big-log");
  // Once uavsim (not the test's fork before exec; the program proper the
  // launcher runs, uavsim-main) handles SIGTERM (/proc's SigCgt mask), it
  // is reading the spec and then checking its 40 000 points.
  const auto handles_sigterm = [pid = sweep.pid()] {
    const std::string proc = "/proc/" + std::to_string(pid);
    std::error_code ec;
    const std::string main = fs::canonical(UAVSIM_CLI).string() + "-main";
    if (fs::read_symlink(proc + "/exe", ec).string() != main) return false;
    std::istringstream status(ReadFile(proc + "/status"));
    std::string line;
    while (std::getline(status, line))
      if (line.rfind("SigCgt:", 0) == 0)
        return (std::stoull(line.substr(7), nullptr, 16) >> (SIGTERM - 1) & 1) != 0;
    return false;
  };
  REQUIRE(sweep.WaitFor(handles_sigterm));
  kill(sweep.pid(), SIGTERM);
  CHECK(sweep.Wait() == 130);
  CHECK_FALSE(fs::exists(out));
}

TEST_CASE("Sweep: under mpirun the points and tables equal a local run's", "[sim][sweep][slow]") {
  const Reference& ref = Ref();
  const std::string mpirun = FindOnPath("mpirun");
  if (mpirun.empty()) FAIL("mpirun is not on PATH (Debian: apt-get install openmpi-bin)");
  const std::string out = TempDir("sweep-mpi") + "/out";
  const CliResult r =
      RunProgram({mpirun, "-np", "2", "--allow-run-as-root", "--oversubscribe", "--mca", "btl",
                  "self,vader", UAVSIM_CLI, "sweep", ref.spec, "--out", out, "--quiet"});
  INFO("mpirun said: " << r.out << r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(FinishedPoints(out) == FinishedPoints(ref.dir));
  CHECK(PartialFolders(out).empty());
  REQUIRE(fs::exists(out + "/summary.csv"));
  CHECK(ReadFile(out + "/summary.csv") == ref.summary);
  CHECK(ReadFile(out + "/aggregate.csv") == ref.aggregate);
  // Points run by the other rank arrive whole: the same files, the same results.
  CheckSameSweep(ref.dir, out);
}

TEST_CASE("Sweep: shards run their points, merge writes the tables once all are done",
          "[sim][sweep][slow]") {
  const Reference& ref = Ref();
  const std::string root = TempDir("sweep-shards");
  for (const std::vector<std::string>& bad :
       std::vector<std::vector<std::string>>{{"--shard", "2/2"},
                                             {"--shard", "x"},
                                             {"--shard", "1/0"},
                                             {"--shard", "0/"},
                                             {"--shard", "/2"},
                                             {"--shard", "-1/2"},
                                             {"--shard", "1-2"},
                                             {"--jobs", "0"},
                                             {"--jobs", "two"}}) {
    INFO(bad[0] << " " << bad[1]);
    const std::string out = root + "/bad";
    const CliResult r = RunCli({"sweep", ref.spec, "--out", out, bad[0], bad[1]});
    CHECK(r.exit_code == 2);
    CHECK(CountLines(r.err) == 1);
    CHECK_THAT(r.err, Catch::Contains(bad[0]));
    CHECK_FALSE(fs::exists(out));
  }

  const std::string out = root + "/out";
  const CliResult s0 = RunCli({"sweep", ref.spec, "--out", out, "--shard", "0/2"});
  INFO("shard 0: " << s0.out << s0.err);
  CHECK(s0.exit_code == 0);
  CHECK_THAT(s0.out, Catch::Contains(
                         "4 points: 2 run now, 0 already done, 0 failed, 2 left to other shards"));
  CHECK_THAT(s0.out, Catch::Contains("uavsim sweep merge " + out));
  CHECK(FinishedPoints(out) == std::vector<std::string>{"p0000", "p0002"});
  CHECK_FALSE(fs::exists(out + "/summary.csv"));

  const CliResult early = RunCli({"sweep", "merge", out});
  INFO("early merge: " << early.out << early.err);
  CHECK(early.exit_code == 2);
  CHECK(CountLines(early.err) == 1);
  CHECK_THAT(early.err, Catch::Contains("p0001"));
  CHECK_THAT(early.err, Catch::Contains("p0003"));
  CHECK(early.err.find("p0000") == std::string::npos);
  CHECK(early.err.find("p0002") == std::string::npos);
  CHECK_FALSE(fs::exists(out + "/summary.csv"));

  const CliResult s1 = RunCli({"sweep", ref.spec, "--out", out, "--shard", "1/2"});
  INFO("shard 1: " << s1.out << s1.err);
  CHECK(s1.exit_code == 0);
  CHECK_THAT(s1.out, Catch::Contains("4 points: 2 run now, 2 already done, 0 failed"));
  CHECK(FinishedPoints(out) == FinishedPoints(ref.dir));
  const CliResult merged = RunCli({"sweep", "merge", out});
  INFO("merge: " << merged.out << merged.err);
  CHECK(merged.exit_code == 0);
  REQUIRE(fs::exists(out + "/summary.csv"));
  CHECK(ReadFile(out + "/summary.csv") == ref.summary);
  CHECK(ReadFile(out + "/aggregate.csv") == ref.aggregate);
  CheckSameSweep(ref.dir, out);

  // merge of something that is not a sweep folder.
  const CliResult not_sweep = RunCli({"sweep", "merge", root});
  CHECK(not_sweep.exit_code == 2);
  CHECK(CountLines(not_sweep.err) == 1);
}

TEST_CASE("Sweep: a folder made by another spec or base scenario is refused",
          "[sim][sweep][slow]") {
  const std::string root = TempDir("sweep-changed");
  Json base = Json::parse(ReadFile(kDefault));
  WriteFile(root + "/base.json", base.dump(2));
  const std::string spec = root + "/changed.json";
  const std::string original =
      R"({"name": "changed", "scenario": "base.json",
          "set": {"/duration_s": 1, "/pipeline/methods": ["ekf"]}, "seeds": [1]})";
  WriteFile(spec, original);
  const std::string out = root + "/out";
  const CliResult first = RunCli({"sweep", spec, "--out", out, "--quiet"});
  INFO("first: " << first.out << first.err);
  REQUIRE(first.exit_code == 0);
  const std::string record = ReadFile(out + "/sweep.json");
  const std::string summary = ReadFile(out + "/summary.csv");

  const auto refused = [&](const std::string& what) {
    INFO(what);
    const CliResult r = RunCli({"sweep", spec, "--out", out, "--quiet"});
    INFO("stderr: " << r.err);
    CHECK(r.exit_code == 2);
    CHECK(CountLines(r.err) == 1);
    CHECK_THAT(r.err, Catch::Contains("another sweep"));
    // Left as it was.
    CHECK(ReadFile(out + "/sweep.json") == record);
    CHECK(ReadFile(out + "/summary.csv") == summary);
    CHECK(FinishedPoints(out) == std::vector<std::string>{"p0000"});
  };
  WriteFile(spec, R"({"name": "changed", "scenario": "base.json",
      "set": {"/duration_s": 1, "/pipeline/methods": ["ekf"]}, "seeds": [2]})");
  refused("another seed");
  WriteFile(spec, R"({"name": "changed", "scenario": "base.json",
      "set": {"/duration_s": 2, "/pipeline/methods": ["ekf"]}, "seeds": [1]})");
  refused("another set");
  WriteFile(spec, R"({"name": "changed", "scenario": "base.json",
      "set": {"/duration_s": 1, "/pipeline/methods": ["ekf"]}, "seeds": [1],
      "parameters": [{"name": "loss", "pointer": "/links/default/loss/p", "values": [0]}]})");
  refused("a parameter more");
  WriteFile(spec, original);
  base["weather"]["rain_mm_h"] = 5.0;
  WriteFile(root + "/base.json", base.dump(2));
  refused("the base scenario changed");

  // Put back as it was: the same sweep, nothing to run.
  base["weather"]["rain_mm_h"] = 0.0;
  WriteFile(root + "/base.json", base.dump(2));
  const CliResult same = RunCli({"sweep", spec, "--out", out});
  INFO("same: " << same.out << same.err);
  CHECK(same.exit_code == 0);
  CHECK_THAT(same.out, Catch::Contains("1 points: 0 run now, 1 already done"));
  // The same spec named from another working directory is the same sweep.
  const CliResult elsewhere = RunCli({"sweep", "changed.json", "--out", "out"}, root);
  INFO("elsewhere: " << elsewhere.out << elsewhere.err);
  CHECK(elsewhere.exit_code == 0);
  CHECK_THAT(elsewhere.out, Catch::Contains("1 points: 0 run now, 1 already done"));

  // A folder that is not a sweep is not written into.
  const std::string other = root + "/other";
  fs::create_directories(other);
  WriteFile(other + "/keep.txt", "mine");
  const CliResult r = RunCli({"sweep", spec, "--out", other, "--quiet"});
  CHECK(r.exit_code == 2);
  CHECK(CountLines(r.err) == 1);
  CHECK(FileList(other) == std::vector<std::string>{"keep.txt"});
}

TEST_CASE("Sweep: a point that fails costs that point only, a rerun retries it",
          "[sim][sweep][slow]") {
  const std::string root = TempDir("sweep-fail");
  // The learned pipeline's model folder passes the check but cannot be
  // loaded: the "uavloc" case's point fails when it runs, the "ekf" one not.
  const std::string model = root + "/model";
  fs::create_directories(model);
  WriteFile(model + "/model.json", "{}");
  const std::string spec = root + "/fail.json";
  WriteFile(spec, R"({"name": "fail", "scenario": ")" + kDefault + R"(",
      "set": {"/duration_s": 1, "/uavs/0/trajectory/phase_deg": 90, "/pipeline/model": ")" +
                      model + R"("},
      "parameters": [{"name": "method", "cases": [
        {"label": "ekf", "set": {"/pipeline/methods": ["ekf"]}},
        {"label": "uavloc", "set": {"/pipeline/methods": ["uavloc"]}}]}]})");
  const std::string out = root + "/out";
  const CliResult failed = RunCli({"sweep", spec, "--out", out});
  INFO("first: " << failed.out << failed.err);
  CHECK(failed.exit_code == 1);
  CHECK_THAT(failed.out, Catch::Contains("2 points: 1 run now, 0 already done, 1 failed"));
  CHECK_THAT(failed.err, Catch::Contains("point p0001"));
  CHECK(failed.err.find("p0000") == std::string::npos);
  CHECK(FinishedPoints(out) == std::vector<std::string>{"p0000"});
  CHECK(PartialFolders(out).empty());
  CHECK_FALSE(fs::exists(out + "/summary.csv"));
  const std::string manifest = ReadFile(out + "/points/p0000/manifest.json");

  // With the model in place, the same command runs the failed point only.
  for (const auto& e : fs::directory_iterator(std::string(UAVSIM_SOURCE_DIR) + "/models/default"))
    fs::copy_file(e.path(), fs::path(model) / e.path().filename(),
                  fs::copy_options::overwrite_existing);
  const CliResult retried = RunCli({"sweep", spec, "--out", out});
  INFO("retried: " << retried.out << retried.err);
  CHECK(retried.exit_code == 0);
  CHECK_THAT(retried.out, Catch::Contains("2 points: 1 run now, 1 already done, 0 failed"));
  CHECK(FinishedPoints(out) == std::vector<std::string>{"p0000", "p0001"});
  CheckPointsWhole(out);
  CHECK(ReadFile(out + "/points/p0000/manifest.json") == manifest);
  const auto rows = SplitLines(ReadFile(out + "/summary.csv"));
  REQUIRE(rows.size() == 3);
  CHECK_THAT(rows[1], Catch::StartsWith("p0000,ekf,1,"));
  CHECK_THAT(rows[2], Catch::StartsWith("p0001,uavloc,1,"));
}

namespace {
// Whether process `pid` has `path` open.
bool HasOpen(pid_t pid, const std::string& path) {
  std::error_code ec;
  const fs::path target = fs::weakly_canonical(path, ec);
  for (const auto& e : fs::directory_iterator("/proc/" + std::to_string(pid) + "/fd", ec)) {
    std::error_code rl;
    if (fs::read_symlink(e.path(), rl) == target) return true;
  }
  return false;
}

// Whether DIR/.lock names process `pid` as its holder.
bool LockNames(const std::string& dir, pid_t pid) {
  std::error_code ec;
  if (!fs::exists(dir + "/.lock", ec)) return false;
  return ReadFile(dir + "/.lock").rfind(std::to_string(pid) + " ", 0) == 0;
}
}  // namespace

TEST_CASE("Sweep: a second sweep into the same folder is refused naming the first, or waits",
          "[sim][sweep][slow]") {
  // Issue 43: two sweeps with one --out ran the same points, both exited
  // 1 and neither wrote summary.csv.
  const std::string root = TempDir("sweep-lock");
  const std::string spec = root + "/lock.json";
  WriteFile(spec, CheapSpec("lock", R"("seeds": {"from": 1, "count": 8})"));
  const std::string out = root + "/out";
  Background first({"sweep", spec, "--out", out, "--quiet"}, root + "/first");
  REQUIRE(first.WaitFor([&] { return LockNames(out, first.pid()); }));
  const CliResult refused = RunCli({"sweep", spec, "--out", out, "--quiet"});
  INFO(refused.err);
  CHECK(refused.exit_code == 2);
  CHECK(CountLines(refused.err) == 1);
  CHECK_THAT(refused.err, Catch::StartsWith("uavsim sweep: " + out + ": in use by process " +
                                            std::to_string(first.pid()) + " ("));
  CHECK_THAT(refused.err, Catch::EndsWith("pass --wait to wait for it\n"));
  // With --wait it waits (it has the lock file open, the first still holds
  // it), then runs once the first has gone.
  Background second({"sweep", spec, "--out", out, "--quiet", "--wait"}, root + "/second");
  REQUIRE(second.WaitFor([&] { return HasOpen(second.pid(), out + "/.lock"); }));
  CHECK(LockNames(out, first.pid()));
  kill(first.pid(), SIGTERM);
  CHECK(first.Wait() == 130);
  CHECK(second.Wait() == 0);
  INFO(ReadFile(root + "/second.err"));
  CHECK(FinishedPoints(out).size() == 8);
  CHECK(fs::exists(out + "/summary.csv"));
}

TEST_CASE("Sweep: points that share their sensing sense once, to the same results as --no-traces",
          "[sim][sweep][slow]") {
  // The reference senses each seed once (its two loss values share the
  // sensing) and removes its traces when complete.
  const Reference& ref = Ref();
  CHECK(!fs::exists(ref.dir + "/traces"));
  const std::string root = TempDir("sweep-traces");
  const CliResult none =
      RunCli({"sweep", ref.spec, "--out", root + "/none", "--jobs", "2", "--quiet", "--no-traces"});
  INFO(none.err);
  REQUIRE(none.exit_code == 0);
  CheckSameSweep(ref.dir, root + "/none");
  // --keep-traces: one trace per seed.
  const CliResult kept = RunCli(
      {"sweep", ref.spec, "--out", root + "/kept", "--jobs", "2", "--quiet", "--keep-traces"});
  INFO(kept.err);
  REQUIRE(kept.exit_code == 0);
  std::size_t traces = 0;
  for (const auto& e : fs::directory_iterator(root + "/kept/traces"))
    traces += e.path().extension() == ".trace";
  CHECK(traces == 2);
}
