#include "apps/dataset/dataset_export.h"

#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <vector>

#include "apps/dataset/dataset_file.h"
#include "apps/sweep/process_farm.h"
#include "apps/train/train.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "core/progress.h"
#include "pipeline/model_bundle.h"
#include "pipeline/torch_runtime.h"
#include "pipeline/training/dataset_io.h"
#include "results/run_directory.h"
#include "sim/edge_server.h"
#include "sim/version.h"

namespace uavsim::sim {
namespace {

namespace fs = std::filesystem;

const char* const kCommand = "uavsim dataset";

// The folder `out` goes into ("." for a bare name).
fs::path FolderOf(const std::string& out) {
  const fs::path parent = fs::path(out).parent_path();
  return parent.empty() ? fs::path(".") : parent;
}

// What must hold before anything is simulated: `out` may be (re)placed and
// its folder exists (made here) and takes files. Throws core::UsageError.
void CheckOut(const DatasetCommand& c) {
  const std::string& out = c.out_file;
  std::error_code ec;
  if (fs::is_directory(out, ec))
    throw core::UsageError(std::string(kCommand) + ": " + out +
                           ": is a folder; --out names the .h5 file to write");
  if (fs::exists(out, ec) && !c.force)
    throw core::UsageError(std::string(kCommand) + ": " + out +
                           ": already exists; choose another --out or pass --force to replace it");
  const fs::path folder = FolderOf(out);
  fs::create_directories(folder, ec);
  if (ec || !fs::is_directory(folder))
    throw core::UsageError(std::string(kCommand) + ": " + out + ": cannot make its folder " +
                           folder.string() + (ec ? ": " + ec.message() : ""));
  if (::access(folder.c_str(), W_OK | X_OK) != 0)
    throw core::UsageError(std::string(kCommand) + ": " + out + ": cannot write in its folder " +
                           folder.string());
}

// Removes what a killed export of `out` left beside it: temporary files
// "NAME.tmp-PID" and episode folders ".NAME.partial-PID" of processes that
// are gone.
void RemoveStaleTemporaries(const std::string& out) {
  results::RemoveStaleStaging(out);
  const std::string prefix = fs::path(out).filename().string() + ".tmp-";
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(FolderOf(out), ec)) {
    const std::string name = e.path().filename().string();
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string pid = name.substr(prefix.size());
    if (pid.empty() || pid.size() > 9 || pid.find_first_not_of("0123456789") != std::string::npos)
      continue;
    const pid_t owner = static_cast<pid_t>(std::stol(pid));
    if (owner == ::getpid() || results::ProcessAlive(owner)) continue;
    std::error_code rm;
    fs::remove(e.path(), rm);
  }
}

// Removes a folder when it goes out of scope (the episodes' scratch folder).
struct RemoveOnExit {
  std::string dir;
  ~RemoveOnExit() {
    std::error_code ec;
    if (!dir.empty()) fs::remove_all(dir, ec);
  }
};

std::vector<DatasetNode> NodesOf(const Scenario& s) {
  std::vector<DatasetNode> nodes;
  for (const NodeConfig& n : s.nodes) {
    DatasetNode d;
    d.id = n.id;
    d.modality = *core::ModalityFromName(n.sensor.modality());
    d.position_m = n.sensor.pose().position_m;
    d.rpy_deg = n.sensor.pose().rpy_deg;
    d.rate_hz = n.sensor.timing().rate_hz;
    nodes.push_back(d);
  }
  return nodes;
}

// Each sample's latent from the model's encoder of its modality, as the
// node computes it (one LibTorch thread).
std::vector<std::vector<std::vector<float>>> EncodeAll(
    const Scenario& base, const std::vector<pipeline::Episode>& episodes,
    const std::string& manifest, const DatasetCommand& c) {
  pipeline::InitTorch(1, c.seed);
  const auto model = pipeline::UavLocModelFiles::Load(manifest);
  if (model->manifest().layout_hash != LayoutHash(base) && !c.quiet)
    std::cerr << "uavsim: warning: the model " << manifest << " was trained for scenario \""
              << model->manifest().scenario
              << "\" with another world or node layout; its latents may say little here\n";
  std::size_t total = 0;
  for (const pipeline::Episode& e : episodes) total += e.samples.size();
  core::Progress progress("encode latents", static_cast<double>(total), "frames", c.quiet);
  std::vector<std::vector<std::vector<float>>> latents(episodes.size());
  std::size_t done = 0;
  for (std::size_t i = 0; i < episodes.size(); ++i) {
    for (const pipeline::Sample& s : episodes[i].samples) {
      const pipeline::NodeEncoder& encoder = model->encoder(s.modality);
      latents[i].push_back(s.camera ? encoder.Encode(*s.camera) : encoder.Encode(*s.points));
      if (++done % 64 == 0) {
        core::ThrowIfInterrupted();
        progress.Update(static_cast<double>(done));
      }
    }
  }
  progress.Finish();
  return latents;
}

}  // namespace

std::optional<DatasetSummary> RunDatasetExport(const Scenario& base, const DatasetCommand& c) {
  EpisodePlan plan = Defaults(false).plan;
  plan.seed = c.seed;
  if (c.episodes > 0) plan.episodes = c.episodes;
  if (c.episode_s > 0) plan.episode_s = c.episode_s;

  // As `uavsim train`: under mpirun every rank simulates episodes; rank 0
  // alone checks, reads --data, and writes.
  std::string manifest;
  const fs::path out(c.out_file);
  const RemoveOnExit scratch{(FolderOf(c.out_file) / ("." + out.filename().string() + ".partial-" +
                                                      std::to_string(::getpid())))
                                 .string()};
  EpisodeRequest request{c.episodes, c.episode_s <= 0, c.data_file, c.jobs, c.quiet, kCommand};
  std::optional<std::vector<pipeline::Episode>> gathered = GatherEpisodes(
      base, plan, request,
      [&] {
        if (!c.model.empty())
          manifest = CheckEncoderModel(base, c.scenario_file, c.model, kCommand);
        CheckOut(c);
        RemoveStaleTemporaries(c.out_file);
      },
      [&] { return scratch.dir; });
  if (!gathered) return std::nullopt;  // an MPI rank other than 0: its share is simulated
  std::vector<pipeline::Episode>& episodes = *gathered;

  std::vector<std::vector<std::vector<float>>> latents;
  if (!manifest.empty()) latents = EncodeAll(base, episodes, manifest, c);

  DatasetHeader header;
  header.uavsim_version = Version();
  header.uavsim_git_hash = GitHash();
  header.scenario_file = c.scenario_file;
  header.scenario = ResolvedJson(base).dump();
  header.seed = c.seed;
  header.episode_s = plan.episode_s;
  header.window_s = base.pipeline.window_s;
  header.latent_dim = manifest.empty() ? 0 : base.pipeline.latent_dim;
  header.model = manifest;
  header.parts = TrajectoryParts(episodes.size(), c.seed);
  {
    core::Progress progress("write " + c.out_file, static_cast<double>(episodes.size()), "episodes",
                            c.quiet);
    core::WriteViaTemporary(c.out_file, [&](const std::string& tmp) {
      WriteDatasetFile(tmp, header, NodesOf(base), episodes, latents, [&](std::size_t done) {
        core::ThrowIfInterrupted();
        progress.Update(static_cast<double>(done));
      });
    });
    progress.Finish();
  }

  DatasetSummary summary;
  summary.episodes = episodes.size();
  summary.episode_s = plan.episode_s;
  summary.latent_dim = header.latent_dim;
  for (const pipeline::Episode& e : episodes)
    for (const pipeline::Sample& s : e.samples) {
      ++summary.frames[static_cast<int>(s.modality)];
      summary.on_time += s.on_time ? 1 : 0;
    }
  std::error_code ec;
  summary.bytes = fs::file_size(c.out_file, ec);
  return summary;
}

}  // namespace uavsim::sim
