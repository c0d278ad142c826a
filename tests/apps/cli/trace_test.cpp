// Sensing traces (sim/sensing_trace.h) through the built binary: a run that
// replays what another run's nodes sent gives that run's outputs byte for
// byte, whatever its links or methods; a trace that does not fit is refused.
#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "core/json_io.h"
#include "test_support.h"

namespace fs = std::filesystem;
using uavsim::core::Json;
using uavsim::testing::CheckSameRun;
using uavsim::testing::FileList;
using uavsim::testing::ReadFile;
using uavsim::testing::RunCli;
using uavsim::testing::TempDir;
using uavsim::testing::WithoutWallClock;
using uavsim::testing::WriteFile;

namespace {

const std::string kDefault = std::string(UAVSIM_SOURCE_DIR) + "/scenarios/default.json";

std::vector<std::string> TraceFiles(const std::string& dir) {
  std::vector<std::string> f;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) f.push_back(e.path().string());
  return f;
}

// 2 s of the default scenario in fog (sensing and links both see weather),
// with the settings a variant adds.
uavsim::testing::CliResult Run(const std::string& out, std::vector<std::string> extra) {
  std::vector<std::string> args = {"run", kDefault,  "--out",
                                   out,   "--quiet", "--duration",
                                   "2",   "--set",   "/weather/fog_visibility_m=800"};
  args.insert(args.end(), extra.begin(), extra.end());
  return RunCli(args);
}

}  // namespace

TEST_CASE("Trace: a replayed run equals a full run across links and methods", "[sim][slow]") {
  const std::string dir = TempDir("trace-links");
  const std::string traces = dir + "/traces";
  // The trace is written by a run whose links differ from every variant's.
  const auto t = Run(dir + "/traced", {"--trace", traces, "--set", "/links/default/latency_ms=40"});
  INFO(t.err);
  REQUIRE(t.exit_code == 0);
  REQUIRE(TraceFiles(traces).size() == 1);

  const std::vector<std::pair<std::string, std::vector<std::string>>> variants = {
      {"loss", {"--set", "/links/default/loss/p=0.3"}},
      {"jitter",
       {"--set", R"(/links/default/jitter={"type": "pareto", "scale_ms": 20, "shape": 2})"}},
      {"bandwidth", {"--set", "/links/default/bandwidth_mbps=0.05"}},
      {"gilbert_elliott",
       {"--set",
        R"(/links/default/loss={"type": "gilbert_elliott", "p": 0.2, "r": 0.3, "loss_bad": 0.9})"}},
      {"outage",
       {"--set", R"(/links/default/outages=[{"from_s": 0.5, "to_s": 1.2}])", "--set",
        "/pipeline/late_allowance_s=0.05"}},
      {"methods", {"--set", R"(/pipeline/methods=["uavloc", "ekf", "uavloc_lidar"])"}},
  };
  for (const auto& [name, settings] : variants) {
    INFO(name);
    const auto full = Run(dir + "/" + name + "-full", settings);
    INFO(full.err);
    REQUIRE(full.exit_code == 0);
    std::vector<std::string> replay = settings;
    replay.insert(replay.end(), {"--replay", traces});
    const auto r = Run(dir + "/" + name + "-replay", replay);
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    CheckSameRun(dir + "/" + name + "-full", dir + "/" + name + "-replay");
  }
  // The variants differ from one another (the test would pass vacuously
  // if the settings changed nothing).
  CHECK(ReadFile(dir + "/loss-full/packets.csv") != ReadFile(dir + "/jitter-full/packets.csv"));
  CHECK(ReadFile(dir + "/outage-full/estimates.csv") != ReadFile(dir + "/loss-full/estimates.csv"));
}

TEST_CASE(
    "Trace: a trace of other sensing, another version, cut short or with a byte changed is refused",
    "[sim][slow]") {
  const std::string dir = TempDir("trace-refused");
  const std::string traces = dir + "/traces";
  REQUIRE(Run(dir + "/traced", {"--trace", traces}).exit_code == 0);
  const auto files = TraceFiles(traces);
  REQUIRE(files.size() == 1);
  const std::string trace = files.front();

  // Rain changes sensing as well as the links: another key, no trace for it.
  auto r = Run(dir + "/rain", {"--replay", traces, "--set", "/weather/rain_mm_h=5"});
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("no sensing trace") && Catch::Contains(traces));
  CHECK(!fs::exists(dir + "/rain"));
  // So does another seed, and a node moved.
  r = Run(dir + "/seed", {"--replay", traces, "--seed", "7"});
  CHECK(r.exit_code == 2);
  r = Run(dir + "/moved", {"--replay", traces, "--set", "/nodes/1/sensor/pose/position_m/2=3"});
  CHECK(r.exit_code == 2);

  // Another format version, named.
  std::string bytes = ReadFile(trace);
  const std::string original = bytes;
  bytes[12] = 99;  // the u32 version after the 12-byte magic
  WriteFile(trace, bytes);
  r = Run(dir + "/version", {"--replay", traces});
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains(trace) && Catch::Contains("format version 99"));
  CHECK(!fs::exists(dir + "/version"));
  // Cut short.
  WriteFile(trace, original.substr(0, original.size() / 2));
  r = Run(dir + "/short", {"--replay", traces});
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains(trace) && Catch::Contains("cut short"));
  // One byte changed anywhere (the header, frames of each node, the end
  // record, the digest): refused before a byte is used, naming the file
  // and the first bad record (a changed byte once replayed silently into
  // other estimates).
  for (const double at : {0.001, 0.2, 0.35, 0.5, 0.7, 0.9, 0.9995}) {
    INFO("byte at " << at << " of " << original.size());
    std::string flipped = original;
    const auto i = static_cast<std::size_t>(at * static_cast<double>(original.size()));
    flipped[i] = static_cast<char>(flipped[i] ^ 0x10);
    WriteFile(trace, flipped);
    r = Run(dir + "/flipped", {"--replay", traces});
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::StartsWith(trace + ": "));
    CHECK_THAT(r.err, Catch::Contains("corrupt") || Catch::Contains("cut short"));
    CHECK(!fs::exists(dir + "/flipped"));
  }
  // Nothing to record in a replay.
  WriteFile(trace, original);
  r = Run(dir + "/record", {"--replay", traces, "--record", "lidar"});
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("--record"));
  // The intact trace replays.
  r = Run(dir + "/ok", {"--replay", traces});
  INFO(r.err);
  CHECK(r.exit_code == 0);
}

TEST_CASE("Trace: a node's further observations are replayed as sent", "[sim][slow]") {
  // Several targets, max_observations 4 and mtt: the messages carry lists
  // of observations (sensing_trace.h's version 2); the replay sends them all.
  const std::string dir = TempDir("trace-further");
  const std::string traces = dir + "/traces";
  const std::string swarm = std::string(UAVSIM_SOURCE_DIR) + "/scenarios/swarm.json";
  const std::vector<std::string> settings = {"--set", R"(/pipeline/methods=["mtt", "ekf"])",
                                             "--set", "/pipeline/preprocess/max_observations=4"};
  const auto run = [&](const std::string& out, const std::vector<std::string>& extra) {
    std::vector<std::string> args = {"run", swarm, "--out", out, "--quiet", "--duration", "3"};
    args.insert(args.end(), settings.begin(), settings.end());
    args.insert(args.end(), extra.begin(), extra.end());
    return RunCli(args);
  };
  const auto t = run(dir + "/traced", {"--trace", traces});
  INFO(t.err);
  REQUIRE(t.exit_code == 0);
  const auto r = run(dir + "/replayed", {"--replay", traces});
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CheckSameRun(dir + "/traced", dir + "/replayed");
  // And the messages did carry further observations: one observation is
  // at most 16 + 4 x 16 + 24 bytes (header, latent, a camera's anchor).
  std::istringstream packets(ReadFile(dir + "/traced/packets.csv"));
  std::string line;
  std::getline(packets, line);
  CHECK(line.rfind("t_capture_s,node,modality,sequence,bytes,", 0) == 0);
  long most = 0;
  while (std::getline(packets, line)) {
    std::istringstream cells(line);
    std::string cell;
    for (int c = 0; c < 5; ++c) std::getline(cells, cell, ',');
    most = std::max(most, std::stol(cell));
  }
  CHECK(most > 16 + 4 * 16 + 24);
}
