// Bring your own model (issue 22): a TorchScript edge model written with
// Debian's python3-torch runs in the loop as a method of the user's name; it
// is given exactly the latents that reached the edge on time (checked
// against packets.csv, written by another part of the run), steers a beam,
// is scored in metrics.json and in a sweep's summary.csv; a model of the
// wrong signature is refused before the run starts.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "core/json_io.h"
#include "pipeline/training/dataset_io.h"
#include "test_support.h"

namespace {

namespace fs = std::filesystem;
using uavsim::core::Json;
using uavsim::testing::ReadFile;
using uavsim::testing::RunCli;
using uavsim::testing::RunProgram;
using uavsim::testing::TempDir;
using uavsim::testing::WriteFile;

const std::string kDefault = std::string(UAVSIM_SOURCE_DIR) + "/scenarios/default.json";
// Debian's interpreter (python3-torch and python3-h5py are its packages;
// another python3 on $PATH may lack them).
const std::string kPython = "/usr/bin/python3";

std::vector<std::string> Split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(s);
  while (std::getline(in, cell, sep)) out.push_back(cell);
  return out;
}

// Scripts `module_source` (a Python class M(torch.nn.Module)) into `path`.
void Script(const std::string& dir, const std::string& module_source, const std::string& path) {
  const std::string py = dir + "/make.py";
  WriteFile(py, "import torch\nfrom torch import Tensor\n" + module_source +
                    "\ntorch.jit.script(M()).save('" + path + "')\n");
  const auto r = RunProgram({kPython, py});
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
}

// Returns, as the position, how many frames of each modality window L - 1
// holds: the count the edge gave it.
const char* const kCounts = R"(
class M(torch.nn.Module):
    history_windows: int
    def __init__(self):
        super().__init__()
        self.history_windows = 3
    def forward(self, latents: Tensor, offsets_s: Tensor, mask: Tensor) -> Tensor:
        assert latents.dim() == 4 and latents.size(0) == 3 and latents.size(1) == 3
        assert latents.size(3) == 16 and bool((offsets_s >= 0).all())
        assert bool((offsets_s < 0.2).all())
        return mask[-1].sum(-1).to(torch.float64)
)";

// Sweeps the default scenario (2 s, loss 0 and 0.3, one seed) with ekf and
// the TorchScript model `model` as method `name`; returns summary.csv.
std::string SweepWith(const std::string& dir, const std::string& name, const std::string& model) {
  const std::string spec = dir + "/spec.json";
  const Json methods =
      Json::array({"ekf", Json{{"type", "torchscript"}, {"name", name}, {"edge", model}}});
  const Json j = {{"name", "byom"},
                  {"scenario", kDefault},
                  {"set", {{"/duration_s", 2}, {"/pipeline/methods", methods}}},
                  {"parameters", Json::array({Json{{"name", "loss"},
                                                   {"pointer", "/links/default/loss/p"},
                                                   {"values", Json::array({0, 0.3})}}})},
                  {"seeds", {{"from", 1}, {"count", 1}}}};
  WriteFile(spec, j.dump());
  const auto s = RunCli({"sweep", spec, "--out", dir + "/sweep", "--quiet"});
  INFO(s.err);
  REQUIRE(s.exit_code == 0);
  return ReadFile(dir + "/sweep/summary.csv");
}

}  // namespace

TEST_CASE(
    "CLI: a TorchScript model from python3-torch runs in the loop under its name on the "
    "latents that arrived on time, steers a beam and is scored in a sweep",
    "[sim][byom][slow]") {
  const std::string dir = TempDir("byom-run");
  const std::string model = dir + "/counts.pt";
  Script(dir, kCounts, model);
  const std::string methods =
      R"(/pipeline/methods=["ekf",{"type":"torchscript","name":"counts","edge":")" + model +
      R"("}])";
  const std::string out = dir + "/run";
  const auto r = RunCli({"run", kDefault, "--duration", "3", "--out", out, "--quiet", "--set",
                         methods, "--set", "/links/default/loss/p=0.2"});
  INFO(r.err);
  REQUIRE(r.exit_code == 0);

  // What reached the edge by each window's deadline with a latent (more
  // than the 16-byte header of a frame that found nothing), per modality.
  std::map<std::pair<long, int>, int> delivered;  // (window k, modality) -> frames
  const auto packets = Split(ReadFile(out + "/packets.csv"), '\n');
  REQUIRE(packets.size() > 10);
  const auto header = Split(packets[0], ',');
  REQUIRE(header == std::vector<std::string>{"t_capture_s", "node", "modality", "sequence", "bytes",
                                             "window", "status", "t_arrival_s", "latency_s"});
  int lost = 0;
  for (std::size_t i = 1; i < packets.size(); ++i) {
    const auto c = Split(packets[i], ',');
    REQUIRE(c.size() >= 7);  // a lost packet has no arrival time or latency
    if (c[6] != "delivered") {
      ++lost;
      continue;
    }
    if (std::stoi(c[4]) <= 16) continue;
    const int m = c[2] == "camera" ? 0 : c[2] == "lidar" ? 1 : 2;
    ++delivered[{std::stol(c[5]) + 1, m}];
  }
  CHECK(lost > 0);  // the loss made some frames absent

  // The model's answers: one per window from the first with data, each the
  // counts the packets give.
  const auto rows = Split(ReadFile(out + "/estimates.csv"), '\n');
  int answered = 0;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const auto c = Split(rows[i], ',');
    if (c.size() < 5 || c[1] != "counts") continue;
    const long k = std::lround(std::stod(c[0]) / 0.2);
    INFO("window " << k);
    for (int m = 0; m < 3; ++m) CHECK(std::stod(c[2 + m]) == delivered[{k, m}]);
    ++answered;
  }
  CHECK(answered >= 13);  // 15 windows in 3 s; the first with data at the latest the second

  const Json metrics = uavsim::core::LoadJsonFile(out + "/metrics.json");
  CHECK(metrics["rmse_m"].contains("counts"));
  CHECK(metrics["uavloc_model"]["scripted"]["counts"] == model);
  CHECK(ReadFile(out + "/rate_snr.csv").find(",counts,") != std::string::npos);

  // A sweep: a column of its own.
  const auto summary = Split(SweepWith(dir, "counts", model), '\n');
  REQUIRE(summary.size() == 3);
  CHECK(summary[0].find("rmse_counts") != std::string::npos);
}

TEST_CASE("CLI: a TorchScript model of the wrong signature is refused before the run starts",
          "[sim][byom]") {
  const std::string dir = TempDir("byom-refused");
  const std::string model = dir + "/two.pt";
  Script(dir, R"(
class M(torch.nn.Module):
    def forward(self, latents: Tensor, mask: Tensor) -> Tensor:
        return latents.sum() + mask.sum()
)",
         model);
  const std::string out = dir + "/run";
  // The file named relative to the working directory, as --set paths are.
  for (const char* command : {"validate", "run"}) {
    std::vector<std::string> args{
        command, kDefault, "--set",
        R"(/pipeline/methods=["ekf",{"type":"torchscript","name":"mine","edge":"two.pt"}])"};
    if (std::string(command) == "run") args.insert(args.end(), {"--out", out, "--quiet"});
    const auto r = RunCli(args, dir);
    INFO(r.err);
    CHECK(r.exit_code == 2);
    CHECK(r.err.find("/pipeline/methods/1/edge: " + model +
                     ": forward takes 2 arguments: "
                     "expected forward(latents: float32 [L, 3, F, z]") != std::string::npos);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  }
  CHECK_FALSE(fs::exists(out));
}

TEST_CASE(
    "CLI: the Python example trains on uavsim dataset's HDF5 and its model runs in the "
    "loop, in metrics, estimates, beams and a sweep",
    "[sim][byom][slow]") {
  const std::string dir = TempDir("byom-example");
  const std::string h5 = dir + "/data.h5", episodes = dir + "/episodes.bin";
  // 1. The training simulation to HDF5, with the shipped model's latents
  // (the episode file kept for the C++ side of the comparison).
  const auto d = RunCli({"dataset", kDefault, "--episodes", "3", "--episode-s", "3", "--model",
                         std::string(UAVSIM_SOURCE_DIR) + "/models/default", "--data", episodes,
                         "--out", h5, "--quiet"});
  INFO(d.err);
  REQUIRE(d.exit_code == 0);
  // 2. The example, at toy size.
  const auto p =
      RunProgram({kPython, std::string(UAVSIM_SOURCE_DIR) + "/examples/python/train_gru.py", h5,
                  "--out", dir + "/mine.pt", "--seconds", "2", "--history", "4"});
  INFO(p.err);
  REQUIRE(p.exit_code == 0);
  const Json py = uavsim::core::ParseJsonText(p.out, "train_gru.py's output");

  // The Python side read what the C++ side simulated: the same episodes,
  // windows, frames per modality (all and on time) and latent size.
  const std::vector<uavsim::pipeline::Episode> eps = uavsim::pipeline::ReadEpisodes(episodes);
  REQUIRE(eps.size() == 3);
  std::size_t windows = 0;
  int frames[3] = {0, 0, 0}, on_time[3] = {0, 0, 0};
  for (const auto& e : eps) {
    windows += e.window_truth.size();
    for (const auto& s : e.samples) {
      ++frames[static_cast<int>(s.modality)];
      on_time[static_cast<int>(s.modality)] += s.on_time ? 1 : 0;
    }
  }
  CHECK(py["episodes"] == 3);
  CHECK(py["windows"] == windows);
  CHECK(py["latent_dim"] == 16);
  CHECK(py["history_windows"] == 4);
  const char* names[3] = {"camera", "lidar", "radar"};
  for (int m = 0; m < 3; ++m) {
    INFO(names[m]);
    CHECK(py["frames"][names[m]] == frames[m]);
    CHECK(py["on_time"][names[m]] == on_time[m]);
    CHECK(frames[m] > 0);
  }
  CHECK(py["held_out_windows"].get<int>() > 0);
  CHECK(std::isfinite(py["held_out_rmse_m"].get<double>()));

  // 3. The model in the loop, named relative to the working directory.
  const std::string methods =
      R"(/pipeline/methods=["ekf",{"type":"torchscript","name":"mine","edge":"mine.pt"}])";
  const auto r = RunCli(
      {"run", kDefault, "--duration", "3", "--out", dir + "/run", "--quiet", "--set", methods},
      dir);
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  const Json metrics = uavsim::core::LoadJsonFile(dir + "/run/metrics.json");
  REQUIRE(metrics["rmse_m"].contains("mine"));
  CHECK(metrics["rmse_m"]["mine"].is_number());
  CHECK(ReadFile(dir + "/run/estimates.csv").find(",mine,") != std::string::npos);
  CHECK(ReadFile(dir + "/run/rate_snr.csv").find(",mine,") != std::string::npos);
  CHECK(Split(SweepWith(dir, "mine", dir + "/mine.pt"), '\n')[0].find("rmse_mine") !=
        std::string::npos);
}

TEST_CASE(
    "CLI: a TorchScript model's absurd answers are counted, not scored; one that fails at run "
    "time is named with its file and window on one line",
    "[sim][byom]") {
  // Issue 43: 3.3e38 m was scored as an error of 3.3e38 m; a failure said
  // "uavsim: shape '[3]' is invalid for input of size 10" or printed a
  // TorchScript traceback.
  const std::string dir = TempDir("byom-absurd");
  const std::string far = dir + "/far.pt";
  Script(dir, R"(
class M(torch.nn.Module):
    def forward(self, latents: Tensor, offsets_s: Tensor, mask: Tensor) -> Tensor:
        if bool(mask[0, 1].sum() > 0.0):
            return torch.tensor([float('nan'), 0.0, 0.0])
        return torch.tensor([3.3e38, 0.0, 0.0])
)",
         far);
  const auto methods = [](const std::string& name, const std::string& model) {
    return R"(/pipeline/methods=["ekf",{"type":"torchscript","name":")" + name + R"(","edge":")" +
           model + R"("}])";
  };
  const std::string out = dir + "/run";
  const auto r = RunCli(
      {"run", kDefault, "--duration", "1", "--out", out, "--quiet", "--set", methods("far", far)});
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  const Json metrics = uavsim::core::LoadJsonFile(out + "/metrics.json");
  INFO(metrics.dump());
  CHECK(metrics["rmse_m"]["far"].is_null());
  CHECK(metrics["estimated_windows"]["far"] == 0);
  // 5 windows; the first one or two see no latent yet (the default scenario's
  // radar sends from its second frame on: its persistent selection).
  CHECK(metrics["rejected_estimates"]["far"].get<int>() >= 3);
  CHECK(metrics["rejected_estimates"]["ekf"] == 0);
  CHECK(ReadFile(out + "/estimates.csv").find(",far,") == std::string::npos);

  const std::string raises = dir + "/raises.pt";
  Script(dir, R"(
class M(torch.nn.Module):
    def forward(self, latents: Tensor, offsets_s: Tensor, mask: Tensor) -> Tensor:
        if bool(mask.sum() > 0.0):
            raise ValueError("no luck with this window")
        return torch.zeros(3)
)",
         raises);
  for (const bool verbose : {false, true}) {
    std::vector<std::string> args{"run",     kDefault, "--duration",
                                  "1",       "--out",  dir + "/failed",
                                  "--quiet", "--set",  methods("unlucky", raises)};
    if (verbose) args.push_back("--verbose");
    const auto f = RunCli(args);
    INFO(f.err);
    CHECK(f.exit_code == 1);
    CHECK_THAT(f.err, Catch::StartsWith("uavsim: method unlucky: " + raises +
                                        ": forward failed at window "));
    const std::string first = f.err.substr(0, f.err.find('\n'));
    CHECK_THAT(first, Catch::EndsWith("no luck with this window"));
    if (verbose)
      CHECK_THAT(f.err, Catch::Contains("Traceback"));
    else
      CHECK(std::count(f.err.begin(), f.err.end(), '\n') == 1);
    CHECK_FALSE(fs::exists(dir + "/failed"));
  }
}
