// `uavsim train` end to end, the learned pipeline in the run loop, and the
// shipped default model on held-out trajectories.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Core>
#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>
#include <utility>

#include "apps/train/train.h"
#include "core/json_io.h"
#include "pipeline/model_bundle.h"
#include "pipeline/torch_runtime.h"
#include "pipeline/training/dataset_io.h"
#include "pipeline/training/trainer.h"
#include "pipeline/training_config.h"
#include "results/csv.h"
#include "test_support.h"

namespace fs = std::filesystem;
using uavsim::core::Json;
using uavsim::testing::FindOnPath;
using uavsim::testing::ReadFile;
using uavsim::testing::RunCli;
using uavsim::testing::RunProgram;
using uavsim::testing::TempDir;
using uavsim::testing::WriteFile;

namespace {
const std::string kDefault = std::string(UAVSIM_SOURCE_DIR) + "/scenarios/default.json";

const Json& Stage(const Json& report, const std::string& name) {
  for (const Json& s : report["stages"])
    if (s["name"] == name) return s;
  FAIL("no stage " << name);
  static const Json none;
  return none;
}
}  // namespace

TEST_CASE("CLI: train --quick learns, is deterministic, and its model runs in the loop",
          "[sim][train][slow]") {
  const std::string dir = TempDir("train");
  const std::string model = dir + "/model", data = dir + "/episodes.bin";
  // Two episodes at a time (the episodes do not depend on it: see the --jobs test).
  auto r = RunCli(
      {"train", kDefault, "--quick", "--jobs", "2", "--out", model, "--data", data, "--quiet"});
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(r.out.empty());
  for (const char* f :
       {"model.json", "camera.json", "camera.pt", "lidar.json", "lidar.pt", "radar.json",
        "radar.pt", "uavloc.pt", "uavloc.pt.json", "uavloc_anchored.pt", "uavloc_anchored.pt.json",
        "training_report.json", "checksums.sha256"})
    CHECK(fs::exists(model + "/" + f));
  CHECK_FALSE(fs::exists(model + "/checkpoints"));
  CHECK(fs::exists(data));

  // The whole model (fusion + Mamba on the stage-1 latents) on held-out
  // validation trajectories, far below its untrained loss. The anchored
  // head: at least 10x (issue 6); measured 11x (1.28 -> 0.117) on the 3
  // validation episodes of 17; with 12 episodes (2 for validation) 9.4x-12x
  // between trainings that differed little. The paper's head starts higher
  // (its untrained output is the flight region's centre, the anchored one's
  // near a candidate) and measured 8.4x (3.28 -> 0.391; its 10x at toy size
  // is trainer_test.cpp's): at least 5x.
  const Json report = Json::parse(ReadFile(model + "/training_report.json"));
  INFO(report.dump(2));
  CHECK(report["heads"] == Json::array({"paper", "anchored"}));
  CHECK(report["position_loss"] == "mixture");
  for (const auto& [stage, factor] :
       {std::pair{"fusion", 5.0}, std::pair{"fusion_anchored", 10.0}}) {
    INFO(stage);
    const Json& fusion = Stage(report, stage);
    CHECK(fusion["best_validation_loss"].get<double>() * factor <=
          fusion["initial_validation_loss"].get<double>());
  }
  for (const char* method : {"uavloc", "uavloc_anchored"})
    CHECK(report["test"][method]["all"]["rmse_m"].is_number());
  // The classical methods on the same held-out flights, every modality
  // subset, never on more windows than the heads (they answer once a track
  // is confirmed); and every method per weather of the test flights (three
  // of them: --quick's episodes are dry).
  for (const char* method : {"ekf", "anchor_track"}) {
    INFO(method);
    REQUIRE(report["test"].contains(method));
    CHECK(report["test"][method].size() == 7);
    CHECK(report["test"][method]["all"]["windows"].get<int>() > 0);
    CHECK(report["test"][method]["all"]["windows"].get<int>() <=
          report["test"]["uavloc"]["all"]["windows"].get<int>());
  }
  CHECK(report["test_weather_episodes"] == Json({{"clear", 3}}));
  for (const char* method : {"uavloc", "uavloc_anchored", "ekf", "anchor_track"})
    CHECK(report["test_by_weather"][method]["clear"]["all"]["windows"] ==
          report["test"][method]["all"]["windows"]);
  // Every method on the windows all of them counted: one count for all,
  // never more than a method counted alone.
  REQUIRE(report.contains("test_common_windows"));
  const int same = report["test_common_windows"]["ekf"]["all"]["windows"].get<int>();
  CHECK(same > 0);
  for (const char* method : {"uavloc", "uavloc_anchored", "ekf", "anchor_track"}) {
    INFO(method);
    CHECK(report["test_common_windows"][method]["all"]["windows"].get<int>() == same);
    CHECK(same <= report["test"][method]["all"]["windows"].get<int>());
    CHECK(report["test_by_weather_common_windows"][method]["clear"]["all"] ==
          report["test_common_windows"][method]["all"]);
  }
  // Per test episode: its label and weather, and each method over its own
  // windows and the common ones; recombined over the episodes (sum of
  // squared errors, sum of windows) they give the whole test's figures.
  REQUIRE(report["test_episodes"].size() == 3);
  std::set<int> numbers;
  for (const Json& e : report["test_episodes"]) numbers.insert(e["episode"].get<int>());
  CHECK(numbers.size() == 3);
  for (const char* method : {"uavloc", "uavloc_anchored", "ekf", "anchor_track"})
    for (const char* part : {"methods", "common_windows"}) {
      INFO(method << " " << part);
      double squared = 0.0;
      int windows = 0;
      for (const Json& e : report["test_episodes"]) {
        CHECK(e["weather"] == "clear");
        CHECK(e["episode"].get<int>() >= 0);
        CHECK(e["episode"].get<int>() < 17);
        const int n = e[part][method]["windows"].get<int>();
        if (n > 0) squared += n * std::pow(e[part][method]["rmse_m"].get<double>(), 2);
        windows += n;
      }
      const Json& whole = std::string(part) == "methods"
                              ? report["test"][method]["all"]
                              : report["test_common_windows"][method]["all"];
      CHECK(windows == whole["windows"].get<int>());
      CHECK(std::sqrt(squared / windows) == Approx(whole["rmse_m"].get<double>()).epsilon(1e-6));
    }
  // test_estimates.csv holds the classical methods' estimates too: their
  // RMSE from the rows' positions is the report's, window for window.
  {
    std::map<std::string, std::pair<double, int>> sums;  // method -> (squared, windows)
    std::istringstream csv(ReadFile(model + "/test_estimates.csv"));
    std::string line;
    std::getline(csv, line);
    while (std::getline(csv, line)) {
      std::vector<std::string> f;
      std::stringstream row(line);
      for (std::string cell; std::getline(row, cell, ',');) f.push_back(cell);
      REQUIRE(f.size() == 11);
      if (f[1] != "all") continue;
      double squared = 0.0;
      for (int c = 0; c < 3; ++c) squared += std::pow(std::stod(f[4 + c]) - std::stod(f[7 + c]), 2);
      sums[f[0]].first += squared;
      ++sums[f[0]].second;
    }
    for (const char* method : {"uavloc", "ekf", "anchor_track"}) {
      INFO(method);
      const auto [squared, windows] = sums[method];
      CHECK(windows == report["test"][method]["all"]["windows"].get<int>());
      CHECK(std::sqrt(squared / windows) ==
            Approx(report["test"][method]["all"]["rmse_m"].get<double>()).epsilon(1e-5));
    }
  }
  CHECK(Stage(report, "camera")["best_validation_loss"].get<double>() <
        Stage(report, "camera")["initial_validation_loss"].get<double>());
  const Json manifest = Json::parse(ReadFile(model + "/model.json"));
  CHECK_THAT(manifest["note"].get<std::string>(), Catch::Contains("--quick"));
  CHECK_THAT(manifest["note"].get<std::string>(), Catch::Contains("seed 1"));
  CHECK(manifest["latent_dim"] == 16);
  // The resolved training config: every key, --quick's own defaults included.
  const Json defaults = uavsim::pipeline::TrainingConfigJson({});
  REQUIRE(manifest.contains("training"));
  CHECK(manifest["training"].size() == defaults.size());
  CHECK(manifest["training"].dump() ==
        uavsim::pipeline::TrainingConfigJson(uavsim::sim::Defaults(true).training).dump());
  CHECK(manifest["training"]["stage1_lr"] == 2e-3);
  CHECK(manifest["training"]["filter_preference_m"] == defaults["filter_preference_m"]);

  // Training twice from the saved episodes gives the same weights (one
  // epoch per stage: the determinism of every step does not need the whole
  // schedule, and CI time does).
  const auto short_training = [&](const std::string& out) {
    auto t = RunCli({"train", kDefault, "--quick", "--out", out, "--data", data, "--config-set",
                     "/stage1_max_epochs=1", "--config-set", "/stage2_max_epochs=1", "--quiet"});
    INFO(t.err);
    REQUIRE(t.exit_code == 0);
  };
  short_training(dir + "/once");
  short_training(dir + "/again");
  for (const char* f : {"camera.pt", "lidar.pt", "radar.pt", "uavloc.pt", "uavloc_anchored.pt"}) {
    INFO(f);
    CHECK(ReadFile(dir + "/once/" + f) == ReadFile(dir + "/again/" + f));
    CHECK(ReadFile(dir + "/once/" + f) != ReadFile(model + "/" + f));  // it did train less
  }
  // The frame split and a smaller training part, end to end from the
  // command line (one epoch per stage).
  {
    auto t = RunCli({"train", kDefault, "--quick", "--out", dir + "/frame", "--data", data,
                     "--split", "frame", "--train-episodes", "5", "--head", "paper", "--config-set",
                     "/stage1_max_epochs=1", "--config-set", "/stage2_max_epochs=1", "--quiet"});
    INFO(t.err);
    REQUIRE(t.exit_code == 0);
    const Json frame = Json::parse(ReadFile(dir + "/frame/training_report.json"));
    CHECK(frame["split"] == "frame");
    CHECK(Stage(frame, "fusion")["train_items"] == 5);        // the first 5 training episodes
    CHECK(Stage(frame, "fusion")["validation_items"] == 17);  // every flight, its windows
    CHECK(frame["test"]["uavloc"]["all"]["windows"].get<int>() > 0);
    CHECK_THAT(Json::parse(ReadFile(dir + "/frame/model.json"))["note"].get<std::string>(),
               Catch::Contains("windows by frame"));
    CHECK(report["split"] == "trajectory");
  }
  // An existing model folder is not replaced without --force.
  auto exists = RunCli({"train", kDefault, "--quick", "--out", model, "--data", data, "--quiet"});
  CHECK(exists.exit_code == 2);
  CHECK_THAT(exists.err, Catch::Contains("already exists"));

  // The trained model in the loop: every method estimates, with an RMSE
  // and a beam (the scenario's default methods: both heads, the anchor
  // filter alone, the EKF).
  const std::string run = dir + "/run";
  auto rr = RunCli({"run", kDefault, "--out", run, "--duration", "5.9", "--quiet", "--set",
                    "/pipeline/model=" + model});
  INFO(rr.err);
  REQUIRE(rr.exit_code == 0);
  const Json metrics = Json::parse(ReadFile(run + "/metrics.json"));
  for (const char* method : {"uavloc", "uavloc_anchored", "anchor_track", "ekf"}) {
    INFO(method);
    REQUIRE(metrics["rmse_m"][method].is_number());
    CHECK(std::isfinite(metrics["rmse_m"][method].get<double>()));
    CHECK(metrics["estimated_windows"][method].get<int>() > 0);
    CHECK(ReadFile(run + "/estimates.csv").find("," + std::string(method) + ",") !=
          std::string::npos);
    CHECK(ReadFile(run + "/rate_snr.csv").find("," + std::string(method) + ",") !=
          std::string::npos);
  }
  CHECK(metrics["uavloc_model"]["same_layout"] == true);
  CHECK(metrics["uavloc_model"]["heads"] == Json::array({"paper", "anchored"}));

  // rmse_common_m: each method's RMSE over the windows every method
  // estimated, recomputed here from truth.csv and estimates.csv (a 5.9 s
  // run: every window end, 0.2 ... 5.8 s, is a truth row).
  std::map<long, Eigen::Vector3d> truth;  // by time in ms
  std::map<std::string, std::map<long, Eigen::Vector3d>> est;
  const auto rows = [](const std::string& text) {
    std::vector<std::vector<std::string>> out;
    std::istringstream in(text);
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) out.push_back(uavsim::results::SplitCsvLine(line));
    return out;
  };
  const auto ms = [](const std::string& t) { return std::lround(std::stod(t) * 1000.0); };
  for (const auto& c : rows(ReadFile(run + "/truth.csv")))
    truth[ms(c[0])] = {std::stod(c[1]), std::stod(c[2]), std::stod(c[3])};
  for (const auto& c : rows(ReadFile(run + "/estimates.csv")))
    est[c[1]][ms(c[0])] = {std::stod(c[2]), std::stod(c[3]), std::stod(c[4])};
  const std::vector<std::string> methods{"uavloc", "uavloc_anchored", "anchor_track", "ekf"};
  REQUIRE(est.size() == methods.size());
  std::map<std::string, double> sum_sq;
  std::uint64_t common = 0;
  for (const auto& [t, p] : est["uavloc"]) {
    if (!std::all_of(methods.begin(), methods.end(),
                     [&](const std::string& m) { return est[m].count(t) == 1; }))
      continue;
    ++common;
    for (const std::string& m : methods) sum_sq[m] += (est[m][t] - truth.at(t)).squaredNorm();
  }
  CHECK(metrics["common_windows"].get<std::uint64_t>() == common);
  // Every method steers a beam: the rate-vs-SNR curves on common windows
  // are over the same windows, each beam with its rows.
  CHECK(metrics["rate_snr_common_windows"].get<std::uint64_t>() == common);
  CHECK(common > 0);
  const std::string common_rates = ReadFile(run + "/rate_snr_common.csv");
  for (const char* beam : {"perfect", "uavloc", "uavloc_anchored", "anchor_track", "ekf"}) {
    INFO(beam);
    CHECK(common_rates.find("," + std::string(beam) + ",") != std::string::npos);
  }
  if (common > 0) {
    for (const std::string& m : methods)
      CHECK(metrics["rmse_common_m"][m].get<double>() ==
            Approx(std::sqrt(sum_sq[m] / static_cast<double>(common))).epsilon(1e-5));
  } else {
    CHECK(metrics["rmse_common_m"].empty());
  }
}

TEST_CASE("CLI: train and run refuse what they cannot use, naming it", "[sim][train][slow]") {
  const std::string dir = TempDir("train-errors");
  auto few = RunCli({"train", kDefault, "--episodes", "2", "--out", dir + "/m"});
  CHECK(few.exit_code == 2);
  CHECK_THAT(few.err, Catch::Contains("--episodes"));
  auto threads = RunCli({"train", kDefault, "--threads", "x", "--out", dir + "/m"});
  CHECK(threads.exit_code == 2);
  auto bottleneck = RunCli({"train", kDefault, "--bottleneck", "cnn", "--out", dir + "/m"});
  CHECK(bottleneck.exit_code == 2);
  CHECK_THAT(bottleneck.err, Catch::Contains("--bottleneck"));
  auto head = RunCli({"train", kDefault, "--head", "linear", "--out", dir + "/m"});
  CHECK(head.exit_code == 2);
  CHECK_THAT(head.err, Catch::Contains("--head"));
  // The tuning knobs are keys of the training config: a bad value names the
  // file, the key's pointer, the value and the rule, on one line.
  for (const auto& [key, value] :
       std::vector<std::pair<std::string, std::string>>{{"selection_weight", "-1"},
                                                        {"selection_weight", "\"x\""},
                                                        {"filter_preference_m", "-0.1"},
                                                        {"offset_calibration_radius_m", "-1"},
                                                        {"offset_calibration_radius_m", "1.5"},
                                                        {"stage2_plateau_epochs", "-2"},
                                                        {"stage1_lr", "0"},
                                                        {"stage1_label_gate_deg", "200"},
                                                        {"position_loss", "\"l1\""}}) {
    const std::string config = dir + "/bad.json";
    WriteFile(config, "{\"" + key + "\": " + value + "}");
    const auto r = RunCli({"train", kDefault, "--out", dir + "/m", "--config", config});
    INFO(key << " " << value << ": " << r.err);
    CHECK(r.exit_code == 2);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK_THAT(r.err, Catch::StartsWith(config + ": /" + key + ": expected "));
    CHECK_THAT(r.err, Catch::Contains(", got " + value));
  }
  CHECK_FALSE(fs::exists(dir + "/m"));

  auto missing = RunCli({"run", kDefault, "--out", dir + "/r", "--quiet", "--set",
                         "/pipeline/model=" + dir + "/nothing-here"});
  CHECK(missing.exit_code == 2);
  CHECK_THAT(missing.err, Catch::Contains("/pipeline/model"));
  // The shipped model sends 16 values; a scenario asking for 8 needs its own.
  auto z8 = RunCli({"run", kDefault, "--out", dir + "/r", "--quiet", "--duration", "1", "--set",
                    "/pipeline/latent_dim=8"});
  CHECK(z8.exit_code == 2);
  CHECK_THAT(z8.err, Catch::Contains("/pipeline/latent_dim"));
  CHECK_THAT(z8.err, Catch::Contains("uavsim train"));
  CHECK_FALSE(fs::exists(dir + "/r"));
}

TEST_CASE("CLI: train reads its tuning from --config; the old flags name their keys",
          "[sim][train][slow]") {
  const std::string dir = TempDir("train-config");
  // A misspelt key: did you mean, one line, exit 2, nothing written.
  WriteFile(dir + "/typo.json", "{\"selection_weigth\": 2}");
  auto typo = RunCli({"train", kDefault, "--out", dir + "/m", "--config", dir + "/typo.json"});
  CHECK(typo.exit_code == 2);
  CHECK(typo.err == dir +
                        "/typo.json: /selection_weigth: unknown key (did you mean "
                        "\"selection_weight\"?)\n");
  // --config-set overrides the file, and is checked as strictly.
  auto set = RunCli({"train", kDefault, "--out", dir + "/m", "--config",
                     std::string(UAVSIM_SOURCE_DIR) + "/scenarios/training/default.json",
                     "--config-set", "/window_dropout=2"});
  CHECK(set.exit_code == 2);
  CHECK_THAT(set.err, Catch::EndsWith("/window_dropout: expected a number in [0, 1], got 2\n"));
  CHECK(std::count(set.err.begin(), set.err.end(), '\n') == 1);
  auto missing = RunCli({"train", kDefault, "--out", dir + "/m", "--config", dir + "/none.json"});
  CHECK(missing.exit_code == 2);
  CHECK_THAT(missing.err, Catch::StartsWith(dir + "/none.json"));
  // The flags the config replaced: refused by name, with the key instead.
  for (const auto& [flag, value, key] :
       std::vector<std::tuple<std::string, std::string, std::string>>{
           {"--lr", "1e-3", "stage1_lr and stage2_lr"},
           {"--selection-weight", "1", "selection_weight"},
           {"--filter-preference", "2", "filter_preference_m"},
           {"--offset-calibration", "1", "offset_calibration_radius_m"},
           {"--plateau", "6", "stage2_plateau_epochs"},
           {"--position-loss", "mean", "position_loss"},
           {"--label-gate", "3,3", "stage1_label_gate_m and stage1_label_gate_deg"}}) {
    const auto r = RunCli({"train", kDefault, "--out", dir + "/m", flag, value});
    INFO(flag << ": " << r.err);
    CHECK(r.exit_code == 2);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK_THAT(r.err, Catch::StartsWith("uavsim train: " + flag + " was replaced by"));
    CHECK_THAT(r.err, Catch::Contains(key));
    CHECK_THAT(r.err, Catch::Contains("--config"));
  }
  CHECK_FALSE(fs::exists(dir + "/m"));
  // --help names every key and the file that spells them out.
  const auto help = RunCli({"train", "--help"});
  CHECK(help.exit_code == 0);
  CHECK_THAT(help.out, Catch::Contains("scenarios/training/default.json"));
  const Json keys = uavsim::pipeline::TrainingConfigJson({});
  for (const auto& [key, value] : keys.items()) {
    INFO(key);
    CHECK_THAT(help.out, Catch::Contains(key));
  }
}

TEST_CASE("Training config: defaults, --quick's overrides, then the file, then --config-set",
          "[sim][train]") {
  using uavsim::pipeline::TrainingConfigJson;
  using uavsim::sim::ResolveTrainingConfig;
  const std::string dir = TempDir("train-config-resolve");
  // No file: the defaults; --quick changes its own keys only.
  CHECK(TrainingConfigJson(ResolveTrainingConfig(false, "")).dump() ==
        TrainingConfigJson({}).dump());
  const auto quick = ResolveTrainingConfig(true, "");
  CHECK(quick.stage1_lr == 2e-3);
  CHECK(quick.stage2_lr == 2e-3);
  CHECK(quick.stage2_max_epochs == 40);
  CHECK(quick.filter_preference_m == uavsim::pipeline::TrainingConfig{}.filter_preference_m);
  CHECK(uavsim::sim::Defaults(true).plan.episodes == 17);
  CHECK(uavsim::sim::Defaults(false).plan.episodes == uavsim::sim::EpisodePlan{}.episodes);
  // {} is a valid file; a file's keys win over --quick's, --config-set over both.
  WriteFile(dir + "/empty.json", "{}");
  CHECK(TrainingConfigJson(ResolveTrainingConfig(false, dir + "/empty.json")).dump() ==
        TrainingConfigJson({}).dump());
  WriteFile(dir + "/t.json", "{\"stage1_lr\": 5e-4, \"position_loss\": \"mean\"}");
  const auto t = ResolveTrainingConfig(true, dir + "/t.json", {"/position_loss=mixture"});
  CHECK(t.stage1_lr == 5e-4);
  CHECK(t.stage2_lr == 2e-3);
  CHECK(t.mixture_loss);
  const auto set_only = ResolveTrainingConfig(false, "", {"/stage2_plateau_epochs=0"});
  CHECK(set_only.stage2_plateau_epochs == 0);
  CHECK(uavsim::testing::ConfigErrorOf([&] { ResolveTrainingConfig(false, "", {"/layers=0"}); }) ==
        "--config-set: /layers: expected an integer in [1, 64], got 0");
}

TEST_CASE("Training episodes are split by trajectory, 70/15/15", "[sim][train]") {
  std::vector<uavsim::pipeline::Episode> episodes(20);
  for (std::size_t i = 0; i < episodes.size(); ++i) episodes[i].label = std::to_string(i);
  const auto d = uavsim::sim::SplitByTrajectory(episodes, 7);
  CHECK(d.train.size() == 14);
  CHECK(d.validation.size() == 3);
  CHECK(d.test.size() == 3);
  std::set<std::string> seen;
  for (const auto* part : {&d.train, &d.validation, &d.test})
    for (const auto& e : *part) CHECK(seen.insert(e.label).second);  // each episode once
  CHECK(seen.size() == 20);
  const auto small = uavsim::sim::SplitByTrajectory(std::vector<uavsim::pipeline::Episode>(3), 7);
  CHECK(small.train.size() == 1);
  CHECK(small.validation.size() == 1);
  CHECK(small.test.size() == 1);
}

TEST_CASE("Training episodes vary the trajectory, seed, weather and loss within limits",
          "[sim][train]") {
  const auto base = uavsim::sim::LoadScenario(kDefault);
  uavsim::sim::EpisodePlan plan;
  std::set<std::string> types;
  std::set<std::uint64_t> seeds;
  for (int i = 0; i < 12; ++i) {
    std::string label;
    const auto s = uavsim::sim::EpisodeScenario(base, plan, i, &label);  // validated
    types.insert(uavsim::sim::ResolvedJson(s)["uavs"][0]["trajectory"]["type"]);
    seeds.insert(s.seed);
    CHECK(s.duration_s == plan.episode_s);
    CHECK(s.pipeline.methods.empty());
    CHECK(s.nodes.size() == base.nodes.size());
    CHECK_FALSE(label.empty());
  }
  CHECK(types == std::set<std::string>{"orbit", "figure8", "random"});
  CHECK(seeds.size() == 12);
  // The same plan draws the same episode.
  CHECK(uavsim::sim::ResolvedJson(uavsim::sim::EpisodeScenario(base, plan, 5)) ==
        uavsim::sim::ResolvedJson(uavsim::sim::EpisodeScenario(base, plan, 5)));
  // Every drawn trajectory keeps the target's speed and acceleration limits
  // (EpisodeScenario validates; a figure eight once exceeded them at i = 58).
  for (int i = 0; i < 600; ++i) {
    INFO("episode " << i);
    CHECK_NOTHROW(uavsim::sim::EpisodeScenario(base, plan, i));
  }
}

TEST_CASE("Training episodes draw the target's size and flight region from its episodes lists",
          "[sim][train]") {
  const auto plain = uavsim::sim::LoadScenario(kDefault);
  auto base = plain;
  const std::vector<Eigen::Vector3d> sizes{
      {0.35, 0.28, 0.11}, {0.47, 0.59, 0.22}, {0.81, 0.67, 0.43}};
  base.uavs[0].episodes.sizes_m = sizes;
  uavsim::sim::EpisodePlan plan;
  std::set<std::size_t> drawn;
  for (int i = 0; i < 30; ++i) {
    const auto s = uavsim::sim::EpisodeScenario(base, plan, i);
    const auto it = std::find(sizes.begin(), sizes.end(), s.uavs[0].size_m);
    REQUIRE(it != sizes.end());
    drawn.insert(static_cast<std::size_t>(it - sizes.begin()));
    // Drawn last: the rest of the episode is the one drawn without sizes.
    Json with = uavsim::sim::ResolvedJson(s);
    Json without = uavsim::sim::ResolvedJson(uavsim::sim::EpisodeScenario(plain, plan, i));
    with["uavs"][0].erase("size_m");
    with["uavs"][0].erase("episodes");
    without["uavs"][0].erase("size_m");
    without["uavs"][0].erase("episodes");
    CHECK(with == without);
  }
  CHECK(drawn.size() == 3);
  // Regions: episode i flies in regions[(i / 3) % 2]; a random flight keeps
  // to the box, an orbit or figure eight flies at an altitude inside it.
  auto regions = plain;
  uavsim::sim::FlightBoxConfig low, high;
  low.min_m = {-40, -40, 14};
  low.max_m = {40, 40, 30};
  high.min_m = {20, -50, 30};
  high.max_m = {120, 50, 100};
  regions.uavs[0].episodes.regions = {low, high};
  for (int i = 0; i < 24; ++i) {
    INFO("episode " << i);
    const auto s = uavsim::sim::EpisodeScenario(regions, plan, i);
    const auto& box = (i / 3) % 2 == 0 ? low : high;
    const auto& t = s.uavs[0].trajectory;
    if (t.type == uavsim::core::TrajectoryType::kRandom) {
      CHECK(t.min_m == box.min_m);
      CHECK(t.max_m == box.max_m);
    } else {
      CHECK(t.center_m.z() >= box.min_m.z());
      CHECK(t.center_m.z() <= box.max_m.z());
    }
  }
  // A box must not be empty.
  Json doc = uavsim::sim::ResolvedJson(plain);
  doc["uavs"][0]["episodes"]["regions"] =
      Json::parse(R"([{"min_m": [0, 0, 50], "max_m": [10, 10, 40]}])");
  CHECK_THAT(
      uavsim::testing::ConfigErrorOf([&] { uavsim::sim::ScenarioFromJson(doc, "e.json", "."); }),
      Catch::StartsWith("e.json: /uavs/0/episodes/regions/0/max_m: min_m[2] (50) must be less"));
}

TEST_CASE("The default model: three modalities beat each single one on held-out trajectories",
          "[sim][train][slow]") {
  uavsim::pipeline::InitTorch(1, 1);
  const auto base = uavsim::sim::LoadScenario(kDefault);
  // Trajectories the default model never saw (it was trained on seed 1's draws).
  uavsim::sim::EpisodePlan plan;
  plan.seed = 4242;
  plan.episodes = 3;
  plan.episode_s = 20.0;
  plan.vary_weather = false;
  const auto episodes = uavsim::sim::SimulateEpisodes(base, plan, true);
  const auto evaluations =
      uavsim::pipeline::EvaluateModel(uavsim::pipeline::DefaultModelPath(), episodes);
  REQUIRE(evaluations.size() == 2);  // both heads ship
  for (const auto& [method, ev] : evaluations) {
    std::string summary = method + ": ";
    for (const auto& [k, v] : ev.rmse_m)
      summary += k + " " + std::to_string(v) + " m over " + std::to_string(ev.windows.at(k)) + "; ";
    INFO(summary);
    REQUIRE(std::isfinite(ev.rmse_m.at("all")));
    CHECK(ev.windows.at("all") > 200);
    for (const char* single : {"camera", "lidar", "radar"}) {
      INFO(single << " " << ev.rmse_m.at(single) << " m, all " << ev.rmse_m.at("all") << " m");
      CHECK(ev.rmse_m.at("all") < ev.rmse_m.at(single));
    }
  }
}

TEST_CASE(
    "CLI: train --jobs 2 and mpirun simulate the episodes one job does, byte for byte, and "
    "extend a saved set exactly",
    "[sim][train][slow]") {
  const std::string dir = TempDir("train-jobs");
  // Short episodes and one epoch a stage: this is about the episodes.
  const std::vector<std::string> common{"train",
                                        kDefault,
                                        "--quick",
                                        "--episode-s",
                                        "4",
                                        "--config-set",
                                        "/stage1_max_epochs=1",
                                        "--config-set",
                                        "/stage2_max_epochs=1",
                                        "--quiet"};
  // Trains into dir/NAME on the episodes file dir/DATA.bin.
  const auto train = [&](const std::string& name, const std::string& data,
                         std::vector<std::string> extra, const std::string& launcher = "") {
    std::vector<std::string> args = common;
    args.insert(args.end(), {"--out", dir + "/" + name, "--data", dir + "/" + data + ".bin"});
    args.insert(args.end(), extra.begin(), extra.end());
    if (launcher.empty()) return RunCli(args);
    std::vector<std::string> argv{launcher,          "-np",   "2",   "--allow-run-as-root",
                                  "--oversubscribe", "--mca", "btl", "self,vader",
                                  UAVSIM_CLI};
    argv.insert(argv.end(), args.begin(), args.end());
    return RunProgram(argv);
  };
  const auto one = train("one", "one", {"--episodes", "3", "--jobs", "1"});
  INFO(one.err);
  REQUIRE(one.exit_code == 0);
  const auto two = train("two", "two", {"--episodes", "3", "--jobs", "2"});
  INFO(two.err);
  REQUIRE(two.exit_code == 0);
  const std::string episodes = ReadFile(dir + "/one.bin");
  CHECK(episodes.size() > 1000);
  CHECK(ReadFile(dir + "/two.bin") == episodes);
  // The same episodes train the same weights; no scratch folder is left.
  for (const char* f : {"camera.pt", "uavloc.pt"}) {
    INFO(f);
    CHECK(ReadFile(dir + "/one/" + f) == ReadFile(dir + "/two/" + f));
  }
  for (const auto& e : fs::recursive_directory_iterator(dir))
    CHECK(e.path().filename().string().find("partial") == std::string::npos);

  const std::string mpirun = FindOnPath("mpirun");
  if (mpirun.empty()) FAIL("mpirun is not on PATH (Debian: apt-get install openmpi-bin)");
  const auto ranks = train("mpi", "mpi", {"--episodes", "3", "--jobs", "1"}, mpirun);
  INFO("mpirun said: " << ranks.out << ranks.err);
  REQUIRE(ranks.exit_code == 0);
  CHECK(ReadFile(dir + "/mpi.bin") == episodes);
  CHECK(ReadFile(dir + "/mpi/uavloc.pt") == ReadFile(dir + "/one/uavloc.pt"));

  // --episodes beyond what --data holds: the missing episodes are simulated
  // (in this process, by two jobs, by two ranks) and the file becomes what a
  // fresh simulation of all of them writes.
  const auto five = train("five", "five", {"--episodes", "5"});
  INFO(five.err);
  REQUIRE(five.exit_code == 0);
  const std::string all_five = ReadFile(dir + "/five.bin");
  CHECK(all_five.size() > episodes.size());
  int n = 0;
  for (const std::vector<std::string>& how :
       {std::vector<std::string>{"--jobs", "1"}, {"--jobs", "2"}, {"mpirun"}}) {
    const std::string name = "extended" + std::to_string(n++);
    INFO(name);
    fs::copy_file(dir + "/one.bin", dir + "/" + name + ".bin");
    const bool mpi = how.front() == "mpirun";
    std::vector<std::string> extra{"--episodes", "5"};
    if (!mpi) extra.insert(extra.end(), how.begin(), how.end());
    const auto r = train(name, name, extra, mpi ? mpirun : "");
    INFO(r.out << r.err);
    REQUIRE(r.exit_code == 0);
    CHECK(ReadFile(dir + "/" + name + ".bin") == all_five);
    CHECK(ReadFile(dir + "/" + name + "/uavloc.pt") == ReadFile(dir + "/five/uavloc.pt"));
  }
  // Fewer than the file holds: its first ones (the model of the 3).
  const auto first = train("first", "five", {"--episodes", "3"});
  INFO(first.err);
  REQUIRE(first.exit_code == 0);
  CHECK(ReadFile(dir + "/first/uavloc.pt") == ReadFile(dir + "/one/uavloc.pt"));
  CHECK(ReadFile(dir + "/five.bin") == all_five);
  // Extending a set drawn with another seed or length would mix two sets:
  // refused, naming the file, nothing written.
  for (const std::vector<std::string>& wrong :
       {std::vector<std::string>{"--seed", "2"}, {"--episode-s", "5"}}) {
    std::vector<std::string> args{"train", kDefault,       "--quick", "--episodes",      "6",
                                  "--out", dir + "/wrong", "--data",  dir + "/five.bin", "--quiet"};
    args.insert(args.end(), wrong.begin(), wrong.end());
    const auto r = RunCli(args);
    INFO(r.err);
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains(dir + "/five.bin") && Catch::Contains("cannot extend"));
    CHECK_FALSE(fs::exists(dir + "/wrong"));
    CHECK(ReadFile(dir + "/five.bin") == all_five);
  }

  CHECK(RunCli({"train", kDefault, "--jobs", "0"}).exit_code == 2);
}

TEST_CASE("CLI: an interrupted training leaves no model and no episode file", "[sim][train]") {
  const std::string dir = TempDir("train-interrupted");
  const std::string out = dir + "/model", data = dir + "/episodes.bin";
  const pid_t pid = fork();
  if (pid == 0) {
    const int devnull = open("/dev/null", O_WRONLY);
    dup2(devnull, 1), dup2(devnull, 2);
    execl(UAVSIM_CLI, UAVSIM_CLI, "train", kDefault.c_str(), "--quick", "--out", out.c_str(),
          "--data", data.c_str(), "--quiet", static_cast<char*>(nullptr));
    _exit(127);
  }
  // Wait until the model's staging folder exists (simulation under way).
  bool started = false;
  for (int i = 0; i < 400 && !started; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
    for (auto& e : fs::directory_iterator(dir))
      started = started || e.path().filename().string().rfind(".model.partial-", 0) == 0;
  }
  REQUIRE(started);
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 130);
  CHECK(fs::is_empty(dir));  // no model, no staging, no episode file
}

TEST_CASE(
    "CLI: train --variant trains a variant on shared encoders that runs in the loop under "
    "its name and on modality subsets",
    "[sim][train][slow]") {
  // Issue 20 item 8. The main model: a copy of the shipped default; the
  // variant beside it (FOLDER-VARIANT) on its encoders, stage 2 only (2
  // epochs on 4 short episodes: this checks the plumbing, not the figure).
  const std::string dir = TempDir("train-variant");
  const std::string main = dir + "/default", late = dir + "/default-late_fusion";
  fs::copy(std::string(UAVSIM_SOURCE_DIR) + "/models/default", main, fs::copy_options::recursive);
  const std::vector<std::string> small{"--quick",
                                       "--episodes",
                                       "4",
                                       "--episode-s",
                                       "4",
                                       "--data",
                                       dir + "/e.bin",
                                       "--config-set",
                                       "/stage2_max_epochs=2",
                                       "--quiet"};
  const auto train = [&](std::vector<std::string> args) {
    args.insert(args.begin(), {"train", kDefault});
    args.insert(args.end(), small.begin(), small.end());
    return RunCli(args);
  };
  auto t = train({"--variant", "late_fusion", "--encoders", main, "--out", late});
  INFO(t.err);
  REQUIRE(t.exit_code == 0);
  const Json manifest = Json::parse(ReadFile(late + "/model.json"));
  CHECK(manifest["variant"] == "late_fusion");
  CHECK(manifest["anchored_edge"] == "");
  CHECK(manifest["training"]["fusion"] == "late");
  CHECK_THAT(manifest["note"].get<std::string>(), Catch::Contains("stage-1 encoders from"));
  // The stage-1 keys say how the reused encoders were trained (the shipped
  // model's, not --quick's).
  CHECK(manifest["training"]["stage1_lr"] ==
        Json::parse(ReadFile(main + "/model.json"))["training"]["stage1_lr"]);
  for (const char* part : {"camera.pt", "lidar.pt", "radar.pt"})
    CHECK(ReadFile(late + "/" + part) == ReadFile(main + "/" + part));
  const Json report = Json::parse(ReadFile(late + "/training_report.json"));
  CHECK(report["method"] == "late_fusion");
  CHECK(report["edge"]["fusion"] == "late");
  CHECK(report["stages"].size() == 1);  // stage 2 only
  CHECK(report["test"]["late_fusion"]["all"]["rmse_m"].is_number());
  CHECK(report["test_common_windows"].contains("ekf"));

  // In the loop: the variant, the variant on two modalities, and the
  // paper's pipeline beside it, on the main model's latents.
  const std::string run = dir + "/run";
  auto r =
      RunCli({"run", kDefault, "--out", run, "--duration", "3", "--quiet", "--set",
              "/pipeline/model=" + main, "--set",
              R"(/pipeline/methods=["uavloc","late_fusion","late_fusion[camera+lidar]","ekf"])"});
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  const Json metrics = Json::parse(ReadFile(run + "/metrics.json"));
  for (const char* method : {"uavloc", "late_fusion", "late_fusion[camera+lidar]"}) {
    INFO(method);
    CHECK(metrics["estimated_windows"][method].get<int>() > 0);
    CHECK(std::isfinite(metrics["rmse_m"][method].get<double>()));
  }
  CHECK(metrics["uavloc_model"]["variant"] == "paper");
  CHECK(metrics["uavloc_model"]["variants"]["late_fusion"] == late + "/model.json");
  // The full-modality variant steers a beam, the subset does not.
  const std::string rates = ReadFile(run + "/rate_snr.csv");
  CHECK(rates.find(",late_fusion,") != std::string::npos);
  CHECK(rates.find(",late_fusion[camera+lidar],") == std::string::npos);

  // Refused, exit 2, naming what: an unknown variant; encoders of a
  // variant whose nodes send other latents; the anchored head for a
  // variant; encoders of another scenario's model; a method whose variant
  // has no model beside /pipeline/model; uavloc asked of a variant's model.
  const auto refused = [&](const std::vector<std::string>& args, const std::string& says) {
    INFO(says);
    const auto x = RunCli(args);
    CHECK(x.exit_code == 2);
    CHECK_THAT(x.err, Catch::Contains(says));
  };
  refused({"train", kDefault, "--variant", "nope", "--out", dir + "/x"},
          "--variant expects one of");
  refused({"train", kDefault, "--variant", "raw", "--encoders", main, "--out", dir + "/x"},
          "whose nodes send other latents than raw's");
  refused({"train", kDefault, "--variant", "gru", "--head", "both", "--out", dir + "/x"},
          "trains the paper's head only");
  {
    // An episode file of pre-processed data cannot train the raw variant
    // (nor a raw one the others): the file records what the nodes sent.
    uavsim::pipeline::Episode e;
    e.label = "hand-made";
    e.window_truth.resize(5, Eigen::Vector3d::Zero());
    uavsim::pipeline::WriteEpisodes({e, e, e}, dir + "/pre.bin");
    refused({"train", kDefault, "--variant", "raw", "--episodes", "3", "--data", dir + "/pre.bin",
             "--out", dir + "/x"},
            "pre.bin: episode 0 holds pre-processed data, this scenario's nodes send raw data of "
            "camera, lidar, radar (/pipeline/preprocess/raw)");
    e.raw_modalities = 7;
    uavsim::pipeline::WriteEpisodes({e, e, e}, dir + "/raw.bin");
    refused({"train", kDefault, "--variant", "gru", "--encoders", main, "--episodes", "3", "--data",
             dir + "/raw.bin", "--out", dir + "/x"},
            "raw.bin: episode 0 holds raw data of camera, lidar, radar, this scenario's nodes "
            "send pre-processed data");
    CHECK_FALSE(fs::exists(dir + "/x"));
  }
  refused({"train", kDefault, "--variant", "gru", "--bottleneck", "mlp", "--out", dir + "/x"},
          "contradicts --variant gru");
  {
    const std::vector<std::string> other{
        "train",        kDefault,     "--variant",
        "gru",          "--encoders", std::string(UAVSIM_SOURCE_DIR) + "/models/mmaud_twin",
        "--out",        dir + "/x",   "--quick",
        "--episodes",   "3",          "--data",
        dir + "/e.bin", "--quiet"};
    refused(other, "was trained for scenario \"mmaud_twin\"");
  }
  CHECK_FALSE(fs::exists(dir + "/x"));
  refused({"run", kDefault, "--out", dir + "/r2", "--quiet", "--set", "/pipeline/model=" + main,
           "--set", R"(/pipeline/methods=["ekf","tcn"])"},
          "/pipeline/methods/1: no model of the tcn variant at " + main + "-tcn/model.json");
  refused({"run", kDefault, "--out", dir + "/r2", "--quiet", "--set", "/pipeline/model=" + late,
           "--set", R"(/pipeline/methods=["uavloc"])"},
          "is the late_fusion variant, not the paper's pipeline: list it as method late_fusion");
  refused({"validate", kDefault, "--set", R"(/pipeline/methods=["uavloc[camera+foo]"])"},
          "/pipeline/methods/0: expected one of");
  CHECK_FALSE(fs::exists(dir + "/r2"));

  // The raw variant trains its own encoders on episodes the nodes send
  // without pre-processing, at toy size, and every stage's validation loss
  // falls; it runs as the scenario's model only with raw pre-processing.
  // Six flights (4 / 1 / 1): with one training flight the fusion stage's
  // validation loss did not fall on an AMD EPYC (2026-12-03), though it had
  // elsewhere; one flight is a coin toss, not a test.
  {
    const std::string raw = dir + "/raw";
    auto x = RunCli({"train", kDefault, "--variant", "raw", "--quick", "--episodes", "6",
                     "--episode-s", "4", "--config-set", "/stage1_max_epochs=3", "--config-set",
                     "/stage2_max_epochs=3", "--out", raw, "--quiet"});
    INFO(x.err);
    REQUIRE(x.exit_code == 0);
    const Json rr = Json::parse(ReadFile(raw + "/training_report.json"));
    for (const Json& stage : rr["stages"]) {
      INFO(stage.dump());
      CHECK(stage["best_validation_loss"].get<double>() <
            stage["initial_validation_loss"].get<double>());
    }
    CHECK(rr["test"].contains("raw"));
    refused({"run", kDefault, "--out", dir + "/r2", "--quiet", "--set", "/pipeline/model=" + raw,
             "--set", R"(/pipeline/methods=["raw"])"},
            "/pipeline/preprocess/raw: the model " + raw +
                "/model.json is the raw variant, trained on data without pre-processing");
    auto y = RunCli({"run", kDefault, "--out", dir + "/r3", "--quiet", "--duration", "2", "--set",
                     "/pipeline/model=" + raw, "--set", "/pipeline/preprocess/raw=true", "--set",
                     R"(/pipeline/methods=["raw","ekf"])"});
    INFO(y.err);
    CHECK(y.exit_code == 0);
  }

  // --help lists every variant with its figure.
  const auto help = RunCli({"train", "--help"});
  for (const char* name : {"paper", "gru", "lstm", "tcn", "resample_first", "resample_middle",
                           "resample_random", "no_madw", "no_mica", "no_madw_mica", "early_fusion",
                           "late_fusion", "modality_dropout", "hemis", "mlp_bottleneck", "raw"})
    CHECK_THAT(help.out, Catch::Contains(std::string("\n  ") + name + " "));
}

TEST_CASE("CLI: a second training on one --data file is refused naming the first", "[sim][train]") {
  // Issue 43: two commands extending one episode file at once.
  const std::string dir = TempDir("train-data-lock");
  const std::string data = dir + "/episodes.eps";
  const std::string lock = dir + "/.episodes.eps.lock";
  uavsim::testing::Background first(
      {"train", kDefault, "--quick", "--data", data, "--out", dir + "/m1", "--quiet"},
      dir + "/first");
  REQUIRE(first.WaitFor([&] {
    std::error_code ec;
    return fs::exists(lock, ec) && ReadFile(lock).rfind(std::to_string(first.pid()) + " ", 0) == 0;
  }));
  const auto second =
      RunCli({"train", kDefault, "--quick", "--data", data, "--out", dir + "/m2", "--quiet"});
  INFO(second.err);
  CHECK(second.exit_code == 2);
  CHECK_THAT(second.err, Catch::StartsWith("uavsim train: --data " + data + ": in use by process " +
                                           std::to_string(first.pid()) + " ("));
  CHECK_FALSE(fs::exists(dir + "/m2"));
  kill(first.pid(), SIGTERM);
  CHECK(first.Wait() == 130);
}
