#include "apps/train/train.h"

#include <algorithm>
#include <boost/mpi/collectives.hpp>
#include <boost/mpi/communicator.hpp>
#include <boost/mpi/environment.hpp>
#include <cmath>
#include <deque>
#include <filesystem>
#include <iostream>
#include <iterator>
#include <memory>

#include "apps/sweep/process_farm.h"
#include "apps/train/held_out_scores.h"
#include "core/error.h"
#include "core/file_lock.h"
#include "core/progress.h"
#include "core/rng.h"
#include "core/trajectory.h"
#include "pipeline/model_bundle.h"
#include "pipeline/torch_runtime.h"
#include "pipeline/training/dataset_io.h"
#include "results/run_directory.h"
#include "sim/run.h"

namespace uavsim::sim {
namespace {

namespace fs = std::filesystem;

// Where the scenario's own target flies: the box its trajectory covers over
// the scenario's duration (sampled every 0.25 s, up to 10 minutes).
struct FlightRegion {
  Eigen::Vector3d lo, hi;
  Eigen::Vector3d centre() const { return 0.5 * (lo + hi); }
  Eigen::Vector3d half() const { return 0.5 * (hi - lo); }
};

FlightRegion RegionOf(const Scenario& s) {
  const UavConfig& target = s.uavs[FirstTarget(s)];
  const auto trajectory = core::MakeTrajectory(
      target.trajectory, core::RngStream(s.seed, "uav/" + target.id + "/trajectory"));
  FlightRegion r{Eigen::Vector3d::Constant(1e300), Eigen::Vector3d::Constant(-1e300)};
  const double span = std::min(s.duration_s, 600.0);
  for (double t = 0.0; t <= span; t += 0.25) {
    const Eigen::Vector3d p = trajectory->StateAt(t).position_m;
    r.lo = r.lo.cwiseMin(p);
    r.hi = r.hi.cwiseMax(p);
  }
  // Widen: training should cover the neighbourhood of the scenario's flight.
  r.lo -= Eigen::Vector3d(10.0, 10.0, 10.0);
  r.hi += Eigen::Vector3d(10.0, 10.0, 10.0);
  r.lo.z() = std::max(r.lo.z(), 5.0);
  r.hi.z() = std::max(r.hi.z(), r.lo.z() + 5.0);
  return r;
}

core::Json Vec(const Eigen::Vector3d& v) { return core::Json::array({v.x(), v.y(), v.z()}); }

// A trajectory of type i % 3 inside the region, within the target's limits.
core::Json DrawTrajectory(const core::TrajectoryConfig& limits, const FlightRegion& r, int i,
                          core::RngStream& rng, std::string& label) {
  const double v_max = limits.max_speed_mps, a_max = limits.max_accel_mps2;
  const Eigen::Vector3d c = r.centre(), h = r.half();
  const double h_xy = std::max(5.0, std::max(h.x(), h.y()) - 10.0);
  Eigen::Vector3d centre(c.x() + rng.Uniform(-0.3, 0.3) * h_xy,
                         c.y() + rng.Uniform(-0.3, 0.3) * h_xy, rng.Uniform(r.lo.z(), r.hi.z()));
  core::Json t = {{"max_speed_mps", v_max}, {"max_accel_mps2", a_max}};
  switch (i % 3) {
    case 0: {
      const double radius = std::max(5.0, rng.Uniform(0.4, 1.3) * h_xy);
      const double speed =
          rng.Uniform(0.3, 0.9) * std::min(v_max, std::sqrt(0.95 * a_max * radius));
      t.update({{"type", "orbit"},
                {"center_m", Vec(centre)},
                {"radius_m", radius},
                {"speed_mps", speed},
                {"clockwise", rng.Bernoulli(0.5)},
                {"phase_deg", rng.Uniform(0.0, 360.0)}});
      label = "orbit r " + core::FormatNumber(std::round(radius)) + " m";
      break;
    }
    case 1: {
      const double ax = rng.Uniform(1.0, 2.4) * h_xy, ay = rng.Uniform(0.6, 1.6) * h_xy;
      // Gerono lemniscate x = A sin wt, y = B sin 2wt (A = ax / 2, B = ay / 2;
      // core/trajectory.cpp): speed <= w sqrt(A^2 + 4 B^2), acceleration
      // <= w^2 sqrt(A^2 + 16 B^2); choose the period so both hold.
      const double a = ax / 2, b = ay / 2;
      const double w = std::min(0.9 * v_max / std::hypot(a, 2 * b),
                                std::sqrt(0.9 * a_max / std::hypot(a, 4 * b)));
      const double period = std::max(2 * M_PI / w, rng.Uniform(20.0, 50.0));
      t.update({{"type", "figure8"},
                {"center_m", Vec(centre)},
                {"size_m", {ax, ay}},
                {"period_s", period},
                {"heading_deg", rng.Uniform(0.0, 360.0)}});
      label = "figure8 " + core::FormatNumber(std::round(ax)) + " x " +
              core::FormatNumber(std::round(ay)) + " m";
      break;
    }
    default:
      t.update({{"type", "random"}, {"min_m", Vec(r.lo)}, {"max_m", Vec(r.hi)}});
      label = "random flight";
      break;
  }
  return t;
}

}  // namespace

Scenario EpisodeScenario(const Scenario& base, const EpisodePlan& plan, int i, std::string* label) {
  core::RngStream rng(plan.seed, "train/episode/" + std::to_string(i));
  core::Json doc = ResolvedJson(base);
  std::string what;
  const std::size_t target = FirstTarget(base);
  const EpisodeVariationConfig& vary = base.uavs[target].episodes;
  FlightRegion region;
  if (vary.regions.empty()) {
    region = RegionOf(base);
  } else {
    const FlightBoxConfig& box =
        vary.regions[static_cast<std::size_t>(i / 3) % vary.regions.size()];
    region = {box.min_m, box.max_m};
  }
  doc["uavs"][target]["trajectory"] =
      DrawTrajectory(base.uavs[target].trajectory, region, i, rng, what);
  doc["seed"] = rng.NextU64() >> 12;
  doc["duration_s"] = plan.episode_s;
  doc["name"] = base.name + "-episode-" + std::to_string(i);
  doc["pipeline"]["methods"] = core::Json::array();
  if (plan.vary_weather) {
    doc["weather"]["rain_mm_h"] = rng.Bernoulli(plan.rain_probability)
                                      ? rng.Uniform(plan.rain_min_mm_h, plan.rain_max_mm_h)
                                      : 0.0;
    if (rng.Bernoulli(plan.fog_probability))
      doc["weather"]["fog_visibility_m"] = rng.Uniform(plan.fog_min_m, plan.fog_max_m);
    else
      doc["weather"].erase("fog_visibility_m");
    const double rain = doc["weather"]["rain_mm_h"].get<double>();
    if (rain > 0) what += ", rain " + core::FormatNumber(std::round(rain)) + " mm/h";
    if (doc["weather"].contains("fog_visibility_m"))
      what += ", fog " +
              core::FormatNumber(std::round(doc["weather"]["fog_visibility_m"].get<double>())) +
              " m";
  }
  if (plan.vary_loss) {
    const double p = rng.Uniform(0.0, plan.loss_max);
    for (auto& [name, link] : doc["links"].items())
      link["loss"] = {{"type", "bernoulli"}, {"p", p}};
    what += ", loss " + core::FormatNumber(std::round(p * 100)) + " %";
  }
  // Drawn last, so that a scenario without sizes draws what it drew before.
  if (!vary.sizes_m.empty()) {
    const Eigen::Vector3d size = vary.sizes_m[rng.UniformInt(vary.sizes_m.size())];
    doc["uavs"][0]["size_m"] = Vec(size);
    what += ", size " + core::FormatNumber(size.x()) + " x " + core::FormatNumber(size.y()) +
            " x " + core::FormatNumber(size.z()) + " m";
  }
  if (label) *label = what;
  return ScenarioFromJson(doc, base.name + " (training episode " + std::to_string(i) + ")",
                          base.base_dir);
}

std::uint8_t RawModalities(const Scenario& s) {
  const pipeline::PreprocessConfig& p = s.pipeline.preprocess;
  return static_cast<std::uint8_t>((p.CameraRaw() ? 1 : 0) | (p.LidarRaw() ? 2 : 0) |
                                   (p.RadarRaw() ? 4 : 0));
}

pipeline::Episode SimulateEpisode(const Scenario& s) {
  pipeline::Episode episode;
  RunOptions o;
  o.quiet = true;
  o.collect = &episode;
  RunScenario(s, o);
  episode.raw_modalities = RawModalities(s);
  return episode;
}

namespace {

// Episode i of the plan, simulated and labelled.
pipeline::Episode SimulatePlannedEpisode(const Scenario& base, const EpisodePlan& plan, int i) {
  std::string label;
  const Scenario s = EpisodeScenario(base, plan, plan.first_episode + i, &label);
  pipeline::Episode e = SimulateEpisode(s);
  e.label = label;
  return e;
}

// Each episode in a child process of its own (apps/sweep/process_farm.h), written
// to <folder>/episode.bin; rank 0 reads them back in episode order, so the
// episodes are the same whatever the jobs or ranks.
ProcessFarm EpisodeFarm(const Scenario& base, const EpisodePlan& plan, const fs::path& scratch,
                        const std::string& command) {
  ProcessFarm farm;
  farm.command = command;
  farm.unit = "episodes";
  farm.run = [&base, &plan](std::size_t i, const std::string& dir) {
    fs::create_directories(dir);
    pipeline::WriteEpisodes({SimulatePlannedEpisode(base, plan, static_cast<int>(i))},
                            (fs::path(dir) / "episode.bin").string());
  };
  farm.describe = [&plan](std::size_t i) {
    return "episode " + std::to_string(plan.first_episode + static_cast<int>(i));
  };
  farm.local_dir = [scratch](std::size_t i) { return (scratch / std::to_string(i)).string(); };
  farm.commit_remote = [scratch](std::size_t i, const TaskFiles& files) {
    const fs::path dir = scratch / std::to_string(i);
    fs::create_directories(dir);
    for (const auto& [path, bytes] : files) results::WriteFileAtomic((dir / path).string(), bytes);
  };
  return farm;
}

// Reads the farm's episodes back in order; throws if one failed.
std::vector<pipeline::Episode> CollectEpisodes(const fs::path& scratch, int count,
                                               const FarmCounts& counts,
                                               const std::string& command) {
  if (counts.failed > 0)
    throw std::runtime_error(command + ": " + std::to_string(counts.failed) + " of " +
                             std::to_string(count) +
                             " training episodes failed (their errors are above)");
  std::vector<pipeline::Episode> episodes;
  for (int i = 0; i < count; ++i) {
    std::vector<pipeline::Episode> one =
        pipeline::ReadEpisodes((scratch / std::to_string(i) / "episode.bin").string());
    if (one.size() != 1)
      throw std::runtime_error(command + ": episode " + std::to_string(i) + " file is damaged");
    episodes.push_back(std::move(one.front()));
  }
  return episodes;
}

}  // namespace

std::vector<pipeline::Episode> SimulateEpisodes(const Scenario& base, const EpisodePlan& plan,
                                                bool quiet) {
  std::vector<pipeline::Episode> episodes;
  core::Progress progress("simulate training episodes", plan.episodes, "episodes", quiet);
  for (int i = 0; i < plan.episodes; ++i) {
    episodes.push_back(SimulatePlannedEpisode(base, plan, i));
    progress.Update(i + 1);
  }
  progress.Finish();
  return episodes;
}

std::vector<pipeline::Episode> SimulateEpisodes(const Scenario& base, const EpisodePlan& plan,
                                                const EpisodeJobs& jobs) {
  const bool mpi = jobs.world != nullptr;
  if (jobs.jobs <= 1 && !mpi) return SimulateEpisodes(base, plan, jobs.quiet);
  const ProcessFarm farm = EpisodeFarm(base, plan, jobs.scratch_dir, jobs.command);
  FarmOptions fo;
  fo.jobs = jobs.jobs;
  fo.quiet = jobs.quiet;
  fo.label = "simulate training episodes";
  if (mpi && jobs.world->rank() != 0) {
    RunFarmWorker(*jobs.world, farm, fo);
    return {};
  }
  std::deque<std::size_t> queue;
  for (int i = 0; i < plan.episodes; ++i) queue.push_back(static_cast<std::size_t>(i));
  const FarmCounts counts = mpi ? RunFarmCoordinator(*jobs.world, farm, std::move(queue), fo)
                                : RunFarmLocal(farm, std::move(queue), fo);
  std::vector<pipeline::Episode> episodes =
      CollectEpisodes(jobs.scratch_dir, plan.episodes, counts, jobs.command);
  std::error_code ec;
  fs::remove_all(jobs.scratch_dir, ec);
  return episodes;
}

SavedEpisodes ReadSavedEpisodes(const Scenario& base, const EpisodePlan& plan, int count,
                                bool keep_length, const std::string& file,
                                const std::string& command) {
  SavedEpisodes saved;
  saved.episodes = pipeline::ReadEpisodes(file, core::ThrowIfInterrupted);
  std::vector<pipeline::Episode>& held = saved.episodes;
  // What the nodes sent must be what this scenario's nodes send (a file of
  // pre-processed observations cannot train the raw variant, nor the
  // reverse). A file from before the record holds pre-processed data.
  const auto what = [](std::uint8_t bits) {
    if (bits == 0) return std::string("pre-processed data");
    std::string m;
    for (int i = 0; i < pipeline::kModalityCount; ++i)
      if (bits & (1 << i))
        m += (m.empty() ? "" : ", ") +
             std::string(core::ModalityName(static_cast<core::Modality>(i)));
    return "raw data of " + m;
  };
  const std::uint8_t want_raw = RawModalities(base);
  for (std::size_t i = 0; i < held.size(); ++i) {
    const std::uint8_t raw =
        held[i].raw_modalities == pipeline::Episode::kRawUnknown ? 0 : held[i].raw_modalities;
    if (raw != want_raw)
      throw core::UsageError(command + ": " + file + ": episode " + std::to_string(i) + " holds " +
                             what(raw) + ", this scenario's nodes send " + what(want_raw) +
                             " (/pipeline/preprocess/raw): use another --data file");
  }
  saved.missing = plan;
  EpisodePlan& missing = saved.missing;
  // The length FILE's episodes were simulated for: whole windows of it.
  const auto length_of = [](const pipeline::Episode& e) {
    return e.window_s * static_cast<double>(e.window_truth.size());
  };
  if (!held.empty() && keep_length) missing.episode_s = length_of(held.front());
  const std::size_t want = count > 0 ? static_cast<std::size_t>(count) : held.size();
  if (want <= held.size()) {
    held.resize(want);
    if (!held.empty()) missing.episode_s = length_of(held.front());
    missing.first_episode = static_cast<int>(want);
    missing.episodes = 0;
    return saved;
  }
  // Extending: the set must be this plan's, or the result would mix two.
  const auto refuse = [&file, &command](const std::string& why) {
    throw core::UsageError(command + ": " + file + ": cannot extend these episodes: " + why);
  };
  for (std::size_t i = 0; i < held.size(); ++i) {
    const pipeline::Episode& e = held[i];
    if (std::abs(length_of(e) - missing.episode_s) >= e.window_s)
      refuse("episode " + std::to_string(i) + " is " + core::FormatNumber(length_of(e)) +
             " s long, --episode-s asks for " + core::FormatNumber(missing.episode_s) + " s");
    std::string label;
    EpisodeScenario(base, missing, static_cast<int>(i), &label);
    if (label != e.label)
      refuse("episode " + std::to_string(i) + " is '" + e.label + "' where this scenario" +
             " and seed draw '" + label + "' (made with another scenario, seed or --quick)");
  }
  missing.first_episode = static_cast<int>(held.size());
  missing.episodes = static_cast<int>(want - held.size());
  return saved;
}

namespace {

// SplitByTrajectory's seeded shuffle of n episodes and the number held out
// in each of the test and validation parts: order[j] goes to the test part
// for j < held, to validation for j < 2 held, else to training.
std::vector<std::size_t> TrajectoryOrder(std::size_t n, std::uint64_t seed, std::size_t* held) {
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  core::RngStream rng(seed, "train/split");
  for (std::size_t i = n; i > 1; --i) std::swap(order[i - 1], order[rng.UniformInt(i)]);
  *held = n >= 3 ? std::max<std::size_t>(1, std::lround(0.15 * n)) : 0;
  return order;
}

}  // namespace

std::vector<int> TrajectoryParts(std::size_t n, std::uint64_t seed) {
  std::size_t held = 0;
  const std::vector<std::size_t> order = TrajectoryOrder(n, seed, &held);
  std::vector<int> part(n, 0);
  for (std::size_t j = 0; j < n; ++j) part[order[j]] = j < held ? 2 : j < 2 * held ? 1 : 0;
  return part;
}

pipeline::Dataset SplitByTrajectory(std::vector<pipeline::Episode> episodes, std::uint64_t seed) {
  std::size_t held = 0;
  const std::vector<std::size_t> order = TrajectoryOrder(episodes.size(), seed, &held);
  pipeline::Dataset d;
  for (std::size_t j = 0; j < order.size(); ++j) {
    pipeline::Episode& e = episodes[order[j]];
    (j < held ? d.test : j < 2 * held ? d.validation : d.train).push_back(std::move(e));
  }
  return d;
}

pipeline::Dataset SplitByFrame(std::vector<pipeline::Episode> episodes, std::uint64_t seed) {
  core::RngStream rng(seed, "train/split-frame");
  pipeline::Dataset d;
  d.split = pipeline::DataSplit::kFrame;
  std::size_t counts[3] = {0, 0, 0};  // training, validation, test windows
  for (pipeline::Episode& e : episodes) {
    std::vector<std::uint8_t> part(e.window_truth.size());
    for (std::uint8_t& p : part) {
      const double u = rng.Uniform();
      p = u < 0.15 ? 2 : u < 0.30 ? 1 : 0;
      ++counts[p];
    }
    pipeline::Episode* copies[3];
    d.train.push_back(e);
    d.validation.push_back(e);
    d.test.push_back(std::move(e));
    copies[0] = &d.train.back();
    copies[1] = &d.validation.back();
    copies[2] = &d.test.back();
    for (std::uint8_t j = 0; j < 3; ++j) {
      copies[j]->scored_windows.resize(part.size());
      for (std::size_t k = 0; k < part.size(); ++k)
        copies[j]->scored_windows[k] = part[k] == j ? 1 : 0;
    }
  }
  if (counts[0] == 0 || counts[1] == 0)
    throw std::invalid_argument("train: the frame split left no " +
                                std::string(counts[0] == 0 ? "training" : "validation") +
                                " window (" + std::to_string(counts[0] + counts[1] + counts[2]) +
                                " windows in all)");
  return d;
}

TrainDefaults Defaults(TrainPreset preset) {
  TrainDefaults d;
  if (preset == TrainPreset::kFull) return d;
  d.plan.vary_weather = false;
  pipeline::TrainingConfig& t = d.training;
  // A larger step for the short runs: with the anchor filter's track the
  // untrained head's blend starts lower, and 1e-3 left the fusion validation
  // loss 9.6x below it; 2e-3 with 16 camera epochs 14x (NOTES.md 2026-11-22 (6)).
  t.stage1_lr = t.stage2_lr = 2e-3;
  if (preset == TrainPreset::kToy) {
    d.plan.episodes = 6;  // 4 / 1 / 1 by trajectory
    d.plan.episode_s = 5.0;
    t.stage1_max_epochs = 2;
    t.stage1_patience = 1;
    t.stage1_min_samples_per_epoch = 64;
    t.stage1_max_samples_per_epoch = 64;
    t.stage1_max_validation_samples = 64;
    t.stage2_max_epochs = 2;
    t.stage2_patience = 1;
    t.stage2_sequence_windows = 10;
    t.stage2_min_steps_per_epoch = 2;
    return d;
  }
  // 17: the smallest count whose 15 % validation split is 3 episodes
  // (12 gave 2, and a validation loss that moved 9x-12x between
  // trainings that differed little). Fewer camera epochs to stay under 3
  // minutes.
  d.plan.episodes = 17;
  d.plan.episode_s = 10.0;
  t.stage1_max_epochs = 16;
  t.stage1_patience = 8;
  t.stage1_min_samples_per_epoch = 480;
  t.stage1_max_samples_per_epoch = 480;
  t.stage1_max_validation_samples = 512;
  t.stage2_max_epochs = 40;
  t.stage2_patience = 10;
  t.stage2_sequence_windows = 30;
  return d;
}

pipeline::TrainingConfig ResolveTrainingConfig(bool quick, const std::string& config_file,
                                               const std::vector<std::string>& overrides,
                                               const pipeline::Variant* variant) {
  core::Json doc = core::Json::object();
  if (!config_file.empty()) doc = core::LoadJsonFile(config_file);
  const std::string name = config_file.empty() ? "--config-set" : config_file;
  for (const std::string& o : overrides) ApplyOverride(doc, o, name);
  pipeline::TrainingConfig base = Defaults(quick).training;
  if (variant) base = pipeline::ApplyVariant(*variant, base);
  return pipeline::TrainingConfigFromJson(doc, name, base);
}

namespace {

// The lock of an episode file: ".NAME.lock" beside it (the file itself is
// replaced by a rename when extended, so its own inode cannot hold a lock).
std::string DataLockPath(const std::string& data_file) {
  const fs::path p(data_file);
  return (p.parent_path() / ("." + p.filename().string() + ".lock")).string();
}

// --encoders DIR: a model of this scenario whose encoders other variants can
// use. Throws core::UsageError naming DIR.
void CheckEncoderSource(const Scenario& base, const TrainCommand& c) {
  const std::string path = pipeline::ModelManifestPath(c.encoders_dir);
  pipeline::ModelManifest m;
  try {
    m = pipeline::ReadModelManifest(path);
  } catch (const std::exception& e) {
    throw core::UsageError("uavsim train: --encoders " + c.encoders_dir + ": " + e.what());
  }
  const pipeline::Variant* v = pipeline::FindVariant(m.variant);
  const pipeline::Variant* mine = pipeline::FindVariant(c.variant);
  if (!v || !mine || !pipeline::SameNodes(*v, *mine))
    throw core::UsageError("uavsim train: --encoders " + c.encoders_dir + " is the " + m.variant +
                           " variant, whose nodes send other latents than " + c.variant +
                           "'s: give a model of a variant whose nodes send the same (" +
                           (mine && mine->raw_modalities ? "e.g. raw" : "e.g. paper") + ")");
  if (m.scenario != base.name || m.layout_hash != LayoutHash(base))
    throw core::UsageError("uavsim train: --encoders " + c.encoders_dir +
                           " was trained for scenario \"" + m.scenario +
                           "\" (or another layout), this is \"" + base.name + "\"");
  if (m.latent_dim != base.pipeline.latent_dim)
    throw core::UsageError("uavsim train: --encoders " + c.encoders_dir + " sends latents of " +
                           std::to_string(m.latent_dim) + " values, the scenario asks for " +
                           std::to_string(base.pipeline.latent_dim));
}

// Splits, trains and commits `dir` (the model folder).
pipeline::TrainReport TrainInto(const Scenario& base, const TrainCommand& c,
                                std::vector<pipeline::Episode> episodes, const EpisodePlan& plan,
                                results::RunDirectory& dir);

}  // namespace

std::optional<std::vector<pipeline::Episode>> GatherEpisodes(
    const Scenario& base, EpisodePlan& plan, const EpisodeRequest& request,
    const std::function<void()>& prepare, const std::function<std::string()>& scratch) {
  std::unique_ptr<boost::mpi::environment> env;
  std::unique_ptr<boost::mpi::communicator> world;
  if (UnderMpirun()) {
    env = std::make_unique<boost::mpi::environment>();
    world = std::make_unique<boost::mpi::communicator>();
  }
  return GatherEpisodes(base, plan, request, prepare, scratch, world.get());
}

std::optional<std::vector<pipeline::Episode>> GatherEpisodes(
    const Scenario& base, EpisodePlan& plan, const EpisodeRequest& request,
    const std::function<void()>& prepare, const std::function<std::string()>& scratch,
    boost::mpi::communicator* world) {
  EpisodeJobs jobs{request.jobs, request.quiet, "", world, request.command};
  // What is left to simulate, rank 0 tells the others: [first, first + count)
  // episodes of `length` s.
  const auto share_plan = [&world](EpisodePlan& p) {
    if (!world) return;
    boost::mpi::broadcast(*world, p.first_episode, 0);
    boost::mpi::broadcast(*world, p.episodes, 0);
    boost::mpi::broadcast(*world, p.episode_s, 0);
  };
  if (world && world->rank() != 0) {
    share_plan(plan);
    if (plan.episodes > 0) SimulateEpisodes(base, plan, jobs);
    return std::nullopt;
  }
  std::vector<pipeline::Episode> episodes;
  EpisodePlan todo = plan;                  // all of them, unless --data holds some
  std::optional<core::FileLock> data_lock;  // to the end: the file is read, then extended
  try {
    prepare();
    if (!request.data_file.empty())
      data_lock.emplace(DataLockPath(request.data_file),
                        request.command + ": --data " + request.data_file, request.wait);
    std::error_code ec;
    if (!request.data_file.empty() && fs::is_regular_file(request.data_file, ec)) {
      SavedEpisodes saved = ReadSavedEpisodes(base, plan, request.episodes, request.keep_length,
                                              request.data_file, request.command);
      episodes = std::move(saved.episodes);
      todo = saved.missing;
    }
  } catch (const std::exception& e) {
    if (!world) throw;
    std::cerr << e.what() << "\n";
    world->abort(2);
  }
  share_plan(todo);
  if (todo.episodes > 0) {
    jobs.scratch_dir = scratch();
    std::vector<pipeline::Episode> more = SimulateEpisodes(base, todo, jobs);
    episodes.insert(episodes.end(), std::make_move_iterator(more.begin()),
                    std::make_move_iterator(more.end()));
    if (!request.data_file.empty()) pipeline::WriteEpisodes(episodes, request.data_file);
  }
  plan.episodes = static_cast<int>(episodes.size());
  plan.episode_s = todo.episode_s;
  for (std::size_t i = 0; i < episodes.size(); ++i) episodes[i].index = static_cast<int>(i);
  return episodes;
}

void ApplyVariantNodes(const pipeline::Variant& v, Scenario& s) {
  pipeline::PreprocessConfig& p = s.pipeline.preprocess;
  if (v.raw_modalities & 1) p.camera.raw = true;
  if (v.raw_modalities & 2) p.lidar.raw = true;
  if (v.raw_modalities & 4) p.radar.raw = true;
}

std::optional<pipeline::TrainReport> RunTraining(const Scenario& base, const TrainCommand& c) {
  EpisodePlan plan = Defaults(c.quick).plan;
  plan.seed = c.data_seed.value_or(c.seed);
  if (!c.encoders_dir.empty()) CheckEncoderSource(base, c);
  if (c.episodes > 0) plan.episodes = c.episodes;
  if (c.episode_s > 0) plan.episode_s = c.episode_s;

  // Rank 0 alone (under mpirun) trains and writes the model folder.
  std::optional<results::RunDirectory> dir;  // staged here: the folder is checked before simulating
  EpisodeRequest request{c.episodes, c.episode_s <= 0, c.data_file, c.jobs, c.quiet};
  request.wait = c.wait;
  std::optional<std::vector<pipeline::Episode>> episodes = GatherEpisodes(
      base, plan, request,
      [&] {
        pipeline::InitTorch(c.threads, c.seed);
        dir.emplace(c.out_dir, c.force);
      },
      [&] { return dir->StagingPath("episodes.partial"); });
  if (!episodes) return std::nullopt;  // an MPI rank other than 0: its share is simulated
  return TrainInto(base, c, std::move(*episodes), plan, *dir);
}

pipeline::TrainReport TrainOnEpisodes(const Scenario& base, const TrainCommand& c,
                                      std::vector<pipeline::Episode> episodes,
                                      const EpisodePlan& plan) {
  if (!c.encoders_dir.empty()) CheckEncoderSource(base, c);
  results::RunDirectory dir(c.out_dir, c.force);
  return TrainInto(base, c, std::move(episodes), plan, dir);
}

namespace {

pipeline::TrainReport TrainInto(const Scenario& base, const TrainCommand& c,
                                std::vector<pipeline::Episode> episodes, const EpisodePlan& plan,
                                results::RunDirectory& dir) {
  pipeline::TrainOptions t;
  static_cast<pipeline::TrainingConfig&>(t) = c.training;
  t.seed = c.seed;
  t.quiet = c.quiet;
  t.check_stop = core::ThrowIfInterrupted;
  t.latent_dim = base.pipeline.latent_dim;
  t.window_s = base.pipeline.window_s;
  if (c.mlp_bottleneck) t.bottleneck = pipeline::IbBottleneck::kMlp;
  if (c.score_classical)
    t.score_classical = [&base](const std::vector<pipeline::Episode>& episodes) {
      return ScoreClassicalMethods(base, episodes);
    };
  t.paper_head = c.paper_head;
  t.anchored_head = c.anchored_head;
  t.method = pipeline::VariantMethod(c.variant);
  t.encoders_from = c.encoders_dir;
  pipeline::Dataset data = c.split == pipeline::DataSplit::kFrame
                               ? SplitByFrame(std::move(episodes), c.seed)
                               : SplitByTrajectory(std::move(episodes), c.seed);
  if (c.train_episodes > 0 && static_cast<std::size_t>(c.train_episodes) < data.train.size())
    data.train.resize(static_cast<std::size_t>(c.train_episodes));
  std::string split = std::to_string(data.train.size()) + "/" +
                      std::to_string(data.validation.size()) + "/" +
                      std::to_string(data.test.size()) + " by trajectory";
  if (data.split == pipeline::DataSplit::kFrame) {
    std::size_t windows[3] = {0, 0, 0};
    const std::vector<pipeline::Episode>* parts[3] = {&data.train, &data.validation, &data.test};
    for (int j = 0; j < 3; ++j)
      for (const pipeline::Episode& e : *parts[j])
        for (std::uint8_t scored : e.scored_windows) windows[j] += scored;
    split = std::to_string(windows[0]) + "/" + std::to_string(windows[1]) + "/" +
            std::to_string(windows[2]) + " windows by frame";
  }

  pipeline::ModelManifest manifest;
  manifest.scenario = base.name;
  manifest.variant = c.variant;
  manifest.layout_hash = LayoutHash(base);
  manifest.note = "trained by `" + c.command_line + "` (seed " + std::to_string(c.seed) +
                  (plan.seed != c.seed ? ", episodes drawn by seed " + std::to_string(plan.seed)
                                       : std::string()) +
                  ", " + std::to_string(plan.episodes) + " episodes of " +
                  core::FormatNumber(plan.episode_s) + " s, split " + split +
                  (c.encoders_dir.empty() ? "" : "; stage-1 encoders from " + c.encoders_dir) + ")";
  pipeline::InitTorch(c.threads, c.seed);  // reseed: the weights do not depend on the simulation
  const pipeline::TrainReport report =
      pipeline::TrainUavLoc(data, t, manifest, dir.StagingPath("."));
  dir.Commit();
  return report;
}

}  // namespace

}  // namespace uavsim::sim
