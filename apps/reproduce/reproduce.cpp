#include "apps/reproduce/reproduce.h"

#include <algorithm>
#include <boost/mpi/collectives/broadcast.hpp>
#include <boost/mpi/communicator.hpp>
#include <boost/mpi/environment.hpp>
#include <chrono>
#include <cmath>
#include <ctime>
#include <deque>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "apps/reproduce/reproduce_report.h"
#include "apps/sweep/process_farm.h"
#include "apps/sweep/recorded_folder.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/file_lock.h"
#include "core/interrupt.h"
#include "core/json_io.h"
#include "core/modality.h"
#include "pipeline/torch_runtime.h"
#include "pipeline/training/dataset_io.h"
#include "pipeline/training_config.h"
#include "pipeline/variants.h"
#include "results/run_directory.h"
#include "sim/run.h"

namespace uavsim::sim {
namespace {

namespace fs = std::filesystem;
using core::Json;

constexpr const char* kFormat = "uavsim-reproduce/1";

// The variants other than `base` whose nodes send what base's do: trained
// on base's encoders, stage 2 only (paper: Figs. 11a-14; raw: Fig. 11b).
std::vector<std::string> OnEncodersOf(const std::string& base) {
  std::vector<std::string> out;
  const pipeline::Variant& b = *pipeline::FindVariant(base);
  for (const pipeline::Variant& v : pipeline::Variants())
    if (v.name != base && pipeline::SameNodes(v, b)) out.push_back(v.name);
  return out;
}

std::string ArmId(const std::string& variant, int z, std::uint64_t seed, bool frame = false) {
  return variant + "-z" + std::to_string(z) + "-s" + std::to_string(seed) + (frame ? "-frame" : "");
}

std::string ModelDir(const std::string& dir, const std::string& id) {
  return (fs::path(dir) / "models" / id).string();
}

std::string SetFile(const std::string& dir, const std::string& set) {
  return (fs::path(dir) / "episodes" / (set + ".eps")).string();
}

bool ArmDone(const std::string& dir, const std::string& id) {
  std::error_code ec;
  return fs::is_regular_file(fs::path(ModelDir(dir, id)) / "training_report.json", ec);
}

// The scenario an arm's nodes run: the variant's raw modalities, latent z.
Scenario ArmScenario(const Scenario& base, const ReproduceArm& arm) {
  Scenario s = base;
  s.pipeline.latent_dim = arm.latent_dim;
  ApplyVariantNodes(*pipeline::FindVariant(arm.variant), s);
  return s;
}

// What identifies the data of DIR: a rerun with other episodes, latent sizes
// or training budget is refused.
Json PlanRecord(const Scenario& base, const ReproducePlan& plan, bool quick) {
  return {{"format", kFormat},
          {"scenario", base.name},
          {"layout_hash", LayoutHash(base)},
          {"quick", quick},
          {"episodes", plan.episodes.episodes},
          {"episode_s", plan.episodes.episode_s},
          {"data_seed", plan.episodes.seed},
          {"latent_dims", plan.latent_dims},
          {"training", pipeline::TrainingConfigJson(plan.training)},
          {"equivalence_fraction", plan.equivalence_fraction}};
}

// Keys a plan record may lack when an older uavsim wrote it: added to it,
// not a reason to refuse the folder.
bool AddedLater(const std::string& key) { return key == "equivalence_fraction"; }

// What killed invocations left: temporary files of dead processes, the
// episode sets' scratch folders (their episodes are simulated again).
void RemoveRemains(const std::string& dir) {
  results::RemoveStaleTemporaries(dir);
  results::RemoveStaleTemporaries((fs::path(dir) / "episodes").string());
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(fs::path(dir) / "episodes", ec))
    if (e.path().extension() == ".partial") fs::remove_all(e.path(), ec);
}

// Creates DIR for the plan `record`, or checks that an existing DIR holds
// the same plan (keys added to the record since it was written are added).
void PrepareDir(const std::string& dir, const Json& record) {
  results::RemoveStaleStaging(dir);  // what killed commands left beside it, of any name
  std::optional<Json> old = ReadFolderRecord(dir, "reproduce.json");
  if (!old) {
    CreateRecordedFolder(dir, "reproduce.json", record, {"models", "episodes"});
    return;
  }
  bool added = false;
  for (const auto& [key, value] : record.items()) {
    if (!old->contains(key) && AddedLater(key)) {
      (*old)[key] = value, added = true;
      continue;
    }
    if (!old->contains(key) || (*old)[key] != value)
      throw core::UsageError("uavsim reproduce: " + dir + " holds a reproduction of another " +
                             "plan (" + key + " " +
                             (old->contains(key) ? (*old)[key].dump() : "?") + ", now " +
                             value.dump() + "): use another --out");
  }
  if (added)
    core::WriteFileAtomic((fs::path(dir) / "reproduce.json").string(), old->dump(2) + "\n");
  // A folder carried from another machine (scripts/carry-reproduction)
  // holds no episode sets.
  for (const char* sub : {"models", "episodes"}) fs::create_directories(fs::path(dir) / sub);
  RemoveRemains(dir);
}

// The sets the arms train on, in plan order.
std::vector<std::string> SetsOf(const ReproducePlan& plan) {
  std::vector<std::string> sets;
  for (const ReproduceArm& a : plan.arms)
    if (std::find(sets.begin(), sets.end(), a.set) == sets.end()) sets.push_back(a.set);
  return sets;
}

std::uint8_t MaskOfSet(const ReproducePlan& plan, const std::string& set) {
  for (const ReproduceArm& a : plan.arms)
    if (a.set == set) return pipeline::FindVariant(a.variant)->raw_modalities;
  return 0;
}

// Tab. II: a short run of the scenario per z, nodes pre-processing, no
// learned method (the bytes a node sends do not depend on the weights).
void RunDataRates(const Scenario& base, const ReproducePlan& plan, const std::string& dir,
                  bool quiet) {
  for (int z : plan.latent_dims) {
    const std::string out = (fs::path(dir) / "data_rates" / ("z" + std::to_string(z))).string();
    std::error_code ec;
    if (fs::is_regular_file(fs::path(out) / "metrics.json", ec)) continue;
    Scenario s = base;
    s.pipeline.latent_dim = z;
    s.pipeline.methods = {"ekf"};
    s.pipeline.scripted.clear();
    s.duration_s = plan.rate_run_s;
    RunOptions o;
    o.out_dir = out;
    o.quiet = true;
    o.report = false;
    o.scenario_file = base.name + " (uavsim reproduce, data rates, z " + std::to_string(z) + ")";
    if (!quiet) std::cerr << "uavsim reproduce: data-rate run, z = " << z << "\n";
    RunScenario(s, o);
  }
}

// DIR/invocations.csv gets a row per invocation that got past the
// episodes: when it started, its wall time, what it trained, how it ended
// (reported, failed, interrupted). The row is written as the trainings
// start and again as each ends, reading `killed` until the invocation
// ends: a row left so is an invocation killed (SIGKILL, a machine
// stopped), its wall time and trainings up to its last finished training.
void LogInvocation(const std::string& dir, const std::string& started_utc, double wall_s, int jobs,
                   std::size_t trained, const std::string& ended) {
  const std::string file = (fs::path(dir) / "invocations.csv").string();
  std::error_code ec;
  const std::string old = fs::is_regular_file(file, ec) ? core::ReadFileBytes(file)
                                                        : "started_utc,wall_s,jobs,trained,ended\n";
  const std::string row = started_utc + "," + core::FormatNumber(std::round(wall_s * 10.0) / 10.0) +
                          "," + std::to_string(jobs) + "," + std::to_string(trained) + "," + ended +
                          "\n";
  std::string text;  // every row but this invocation's earlier one, then this one
  std::istringstream lines(old);
  for (std::string line; std::getline(lines, line);)
    if (line.rfind(started_utc + ",", 0) != 0) text += line + "\n";
  core::WriteFileAtomic(file, text + row);
}

std::string UtcNow() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

// The plan's arms: the stage-1 arms of every seed first, so that the farm
// can start the arms that reuse them once they are done.
void AddArms(ReproducePlan& plan) {
  const int z0 = plan.scenario_latent_dim;
  const auto arm = [&](const std::string& variant, int z, std::uint64_t seed,
                       const std::string& encoders, bool edge, bool frame = false) {
    ReproduceArm a;
    a.id = ArmId(variant, z, seed, frame);
    a.variant = variant;
    a.latent_dim = z;
    a.seed = seed;
    a.set = EpisodeSetName(pipeline::FindVariant(variant)->raw_modalities);
    a.encoders = encoders;
    a.edge = edge;
    a.frame_split = frame;
    plan.arms.push_back(a);
  };
  for (int s = 1; s <= plan.seeds; ++s) {
    const auto seed = static_cast<std::uint64_t>(s);
    for (const char* v : {"paper", "raw"})
      for (int z : plan.latent_dims) arm(v, z, seed, "", z == z0);
    for (int z : plan.latent_dims) arm("mlp_bottleneck", z, seed, "", false);
    arm("paper", z0, seed, "", true, true);
    arm("raw_camera", z0, seed, "", true);
    arm("raw_lidar_radar", z0, seed, "", true);
  }
  for (int s = 1; s <= plan.seeds; ++s) {
    const auto seed = static_cast<std::uint64_t>(s);
    for (const char* base : {"paper", "raw"})
      for (const std::string& v : OnEncodersOf(base)) arm(v, z0, seed, ArmId(base, z0, seed), true);
  }
}

}  // namespace

std::string EpisodeSetName(std::uint8_t raw) {
  switch (raw) {
    case 0:
      return "pre";
    case 7:
      return "raw";
    case 1:
      return "raw_camera";
    case 6:
      return "raw_lidar_radar";
    default:
      return "raw" + std::to_string(raw);
  }
}

ReproducePlan MakeReproducePlan(const Scenario& base, const ReproduceOptions& o) {
  ReproducePlan plan;
  const TrainDefaults d = Defaults(false);
  plan.episodes = d.plan;
  plan.episodes.episodes = 30;  // 21 / 4 / 5 flights by trajectory
  plan.episodes.episode_s = 20.0;
  plan.training = d.training;
  // One budget for every arm (the same for the paper's design and its
  // baselines), sized so that every training reaches its validation plateau
  // (issue 41; the best epochs measured at this size: NOTES.md, session
  // 18): stage 1 at most 100 epochs of 1000 observations per modality with
  // patience 15, stage 2 at most 150 epochs with patience 20.
  // trainings.csv records where each stopped.
  // z in {4, 16, 64}, the paper's ends and middle.
  plan.training.stage1_max_epochs = 100;
  plan.training.stage1_patience = 15;
  plan.training.stage1_max_samples_per_epoch = 1000;
  plan.training.stage1_max_validation_samples = 512;
  plan.training.stage2_max_epochs = 150;
  plan.training.stage2_patience = 20;
  plan.latent_dims = {4, 16, 64};
  if (o.quick) {
    // Every arm at toy size: the plan's shape in minutes, not its results
    // (two seeds, three latent sizes: every artefact, within 10 minutes).
    plan.seeds = 2;
    const TrainDefaults toy = Defaults(TrainPreset::kToy);
    plan.episodes.episodes = toy.plan.episodes;
    plan.episodes.episode_s = toy.plan.episode_s;
    plan.episodes.vary_weather = toy.plan.vary_weather;
    plan.training = toy.training;
    plan.rate_run_s = 4.0;
  }
  if (o.episodes > 0) plan.episodes.episodes = o.episodes;
  if (o.seeds > 0) plan.seeds = o.seeds;
  plan.scenario_latent_dim = base.pipeline.latent_dim;
  if (std::find(plan.latent_dims.begin(), plan.latent_dims.end(), plan.scenario_latent_dim) ==
      plan.latent_dims.end()) {
    plan.latent_dims.push_back(plan.scenario_latent_dim);
    std::sort(plan.latent_dims.begin(), plan.latent_dims.end());
  }
  AddArms(plan);
  return plan;
}

namespace {

using EpisodeSets = std::map<std::string, std::vector<pipeline::Episode>>;

// This invocation's start, for its wall time and DIR/invocations.csv.
struct Invocation {
  std::chrono::steady_clock::time_point started = std::chrono::steady_clock::now();
  std::string started_utc = UtcNow();
  double WallS() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  }
};

// The MPI environment and communicator under mpirun (null otherwise).
struct Ranks {
  std::unique_ptr<boost::mpi::environment> env;
  std::unique_ptr<boost::mpi::communicator> world;
  bool coordinator = true;  // rank 0, or no MPI
  Ranks() {
    if (UnderMpirun()) {
      env = std::make_unique<boost::mpi::environment>();
      world = std::make_unique<boost::mpi::communicator>();
    }
    coordinator = !world || world->rank() == 0;
  }
};

// Which of SetsOf(plan) an unfinished training needs (bit i: set i). Rank
// 0 decides and tells the others, so every rank gathers the same sets.
std::uint32_t SetsStillNeeded(const ReproducePlan& plan, const std::string& dir,
                              const Ranks& ranks) {
  const std::vector<std::string> all = SetsOf(plan);
  std::uint32_t needed = 0;
  if (ranks.coordinator)
    for (const ReproduceArm& a : plan.arms)
      if (!ArmDone(dir, a.id))
        needed |= 1u << (std::find(all.begin(), all.end(), a.set) - all.begin());
  if (ranks.world) boost::mpi::broadcast(*ranks.world, needed, 0);
  return needed;
}

// The episode sets an unfinished training needs, each simulated once (every
// rank its share) or read from DIR; a folder whose trainings are all done
// (a finished or carried reproduction) reads none. Rank 0 locks DIR into
// `lock` as it first prepares it.
EpisodeSets SimulateEpisodeSets(const Scenario& base, const ReproducePlan& plan,
                                const ReproduceOptions& o, const std::string& dir,
                                const Ranks& ranks, std::optional<core::FileLock>& lock) {
  EpisodeSets sets;
  const auto prepare = [&] {
    PrepareDir(dir, PlanRecord(base, plan, o.quick));
    if (!lock) lock.emplace(dir + "/.lock", "uavsim reproduce: " + dir, o.wait);
  };
  const std::vector<std::string> all = SetsOf(plan);
  const std::uint32_t needed = SetsStillNeeded(plan, dir, ranks);
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (!(needed & (1u << i))) continue;
    const std::string& set = all[i];
    Scenario s = base;
    pipeline::Variant nodes{"", "", "", "{}", false, MaskOfSet(plan, set)};
    ApplyVariantNodes(nodes, s);
    EpisodePlan p = plan.episodes;
    EpisodeRequest request;
    request.episodes = p.episodes;
    request.data_file = SetFile(dir, set);
    request.jobs = o.jobs;
    request.quiet = o.quiet;
    request.command = "uavsim reproduce";
    const std::string scratch = (fs::path(dir) / "episodes" / (set + ".partial")).string();
    if (ranks.coordinator && !o.quiet)
      std::cerr << "uavsim reproduce: episode set " << set << " (" << p.episodes << " of "
                << p.episode_s << " s)\n";
    request.wait = o.wait;
    std::optional<std::vector<pipeline::Episode>> e = GatherEpisodes(
        s, p, request, prepare,
        [&] {
          std::error_code ec;
          fs::remove_all(scratch, ec);
          return scratch;
        },
        ranks.world.get());
    if (e) sets[set] = std::move(*e);
  }
  if (ranks.coordinator && !lock) {  // no set needed: DIR checked and locked all the same
    try {
      prepare();
    } catch (const std::exception& e) {
      if (!ranks.world) throw;
      std::cerr << e.what() << "\n";
      ranks.world->abort(2);
    }
  }
  return sets;
}

// A set's episodes: those this process gathered, or (a rank other than 0)
// read from DIR, a shared file system.
const std::vector<pipeline::Episode>& EpisodesOf(EpisodeSets& sets, const std::string& dir,
                                                 const std::string& set) {
  auto it = sets.find(set);
  if (it == sets.end())
    it = sets.emplace(set, pipeline::ReadEpisodes(SetFile(dir, set), core::ThrowIfInterrupted))
             .first;
  return it->second;
}

// The index of the arm whose stage-1 encoders arm `a` reuses; nullopt: none.
std::optional<std::size_t> EncoderArm(const ReproducePlan& plan, const ReproduceArm& a) {
  if (a.encoders.empty()) return std::nullopt;
  for (std::size_t i = 0; i < plan.arms.size(); ++i)
    if (plan.arms[i].id == a.encoders) return i;
  return std::nullopt;
}

// In the farm's child: trains arm `a` into model_dir.
void TrainArm(const Scenario& base, const ReproducePlan& plan, const ReproduceOptions& o,
              const std::string& dir, EpisodeSets& sets, const ReproduceArm& a,
              const std::string& model_dir) {
  if (!a.encoders.empty() && !ArmDone(dir, a.encoders))
    throw std::runtime_error("the arm whose encoders it reuses, " + a.encoders + ", did not train");
  const pipeline::Variant& v = *pipeline::FindVariant(a.variant);
  const Scenario s = ArmScenario(base, a);
  TrainCommand c;
  c.out_dir = model_dir;
  c.quiet = true;
  c.seed = a.seed;
  c.data_seed = plan.episodes.seed;
  c.variant = a.variant;
  c.mlp_bottleneck = v.mlp_bottleneck;
  c.encoders_dir = a.encoders.empty() ? "" : ModelDir(dir, a.encoders);
  c.paper_head = a.edge;
  c.anchored_head = false;
  c.score_classical = false;
  c.split = a.frame_split ? pipeline::DataSplit::kFrame : pipeline::DataSplit::kTrajectory;
  c.training = pipeline::ApplyVariant(v, plan.training);
  c.command_line = o.command_line + " (training " + a.id + ")";
  pipeline::InitTorch(1, a.seed);
  TrainOnEpisodes(s, c, EpisodesOf(sets, dir, a.set), plan.episodes);
}

// The farm whose task i is the plan's arm i, in DIR/models/<arm>; an arm
// that reuses another's encoders starts once that arm has ended.
ProcessFarm TrainingFarm(const Scenario& base, const ReproducePlan& plan, const ReproduceOptions& o,
                         const std::string& dir, EpisodeSets& sets) {
  ProcessFarm farm;
  farm.command = "uavsim reproduce";
  farm.unit = "trainings";
  farm.run = [&base, &plan, &o, &dir, &sets](std::size_t i, const std::string& model_dir) {
    TrainArm(base, plan, o, dir, sets, plan.arms[i], model_dir);
  };
  farm.describe = [&plan](std::size_t i) { return "training " + plan.arms[i].id; };
  farm.local_dir = [&plan, &dir](std::size_t i) { return ModelDir(dir, plan.arms[i].id); };
  farm.commit_remote = [&plan, &dir](std::size_t i, const TaskFiles& files) {
    results::RunDirectory run(ModelDir(dir, plan.arms[i].id), false);
    for (const auto& [path, bytes] : files) run.WriteText(path, bytes);
    run.Commit();
  };
  farm.after = [&plan](std::size_t i) { return EncoderArm(plan, plan.arms[i]); };
  return farm;
}

// The order an arm waits in: stage-1 arms on raw LiDAR (the longest, by far)
// first, then the other stage-1 arms, then those that reuse encoders; so
// the longest trainings do not come last and leave a core idle.
int QueueRank(const ReproduceArm& a) {
  if (!a.encoders.empty()) return 2;
  const std::uint8_t raw = pipeline::FindVariant(a.variant)->raw_modalities;
  return raw & (1u << static_cast<int>(core::Modality::kLidar)) ? 0 : 1;
}

// The arms still to train in queue order; those already done counted into
// *already_done.
std::deque<std::size_t> ArmsToTrain(const ReproducePlan& plan, const std::string& dir,
                                    std::size_t* already_done) {
  std::deque<std::size_t> queue;
  for (const int rank : {0, 1, 2})
    for (std::size_t i = 0; i < plan.arms.size(); ++i) {
      const ReproduceArm& a = plan.arms[i];
      if (QueueRank(a) != rank) continue;
      if (ArmDone(dir, a.id)) {
        ++*already_done;
        continue;
      }
      queue.push_back(i);
    }
  return queue;
}

std::size_t ArmsDone(const ReproducePlan& plan, const std::string& dir) {
  std::size_t done = 0;
  for (const ReproduceArm& a : plan.arms) done += ArmDone(dir, a.id);
  return done;
}

// The trainings in one queue (a reuse arm waits for its encoders' arm):
// here, or handed out to the ranks under MPI (a shared file system carries
// the encoders to the rank that reuses them, as it carries the episodes).
void RunTrainings(const ReproducePlan& plan, const std::string& dir, const ProcessFarm& farm,
                  const FarmOptions& fo, const Ranks& ranks, ReproduceOutcome& out) {
  FarmCounts c;
  if (!ranks.coordinator) {
    if (ranks.world) ranks.world->barrier();
    c = RunFarmWorker(*ranks.world, farm, fo);
  } else {
    std::deque<std::size_t> queue = ArmsToTrain(plan, dir, &out.already_done);
    if (ranks.world) {
      ranks.world->barrier();
      c = RunFarmCoordinator(*ranks.world, farm, std::move(queue), fo);
    } else {
      c = RunFarmLocal(farm, std::move(queue), fo);
    }
  }
  out.ran += c.ran;
  out.failed += c.failed;
}

// Tab. II's runs, then every artefact and the report.
void Report(const Scenario& base, const ReproducePlan& plan, const ReproduceOptions& o,
            const std::string& dir, const Invocation& invocation, ReproduceOutcome& out) {
  RunDataRates(base, plan, dir, o.quiet);
  out.wall_s = invocation.WallS();
  LogInvocation(dir, invocation.started_utc, out.wall_s, o.jobs, out.ran, "reported");
  ReproduceReportInputs in;
  in.dir = dir;
  in.scenario = &base;
  in.plan = &plan;
  in.quick = o.quick;
  in.command_line = o.command_line;
  in.trained_now = out.ran;
  out.warnings = WriteReproduceReport(in);
  out.reported = true;
}

}  // namespace

ReproduceOutcome RunReproduce(const Scenario& base, const ReproduceOptions& o) {
  const Invocation invocation;
  if (o.jobs < 1) throw core::UsageError("uavsim reproduce: --jobs needs at least 1");
  const ReproducePlan plan = MakeReproducePlan(base, o);
  if (plan.episodes.episodes < 3)
    throw core::UsageError("uavsim reproduce: --episodes needs at least 3");
  ReproduceOutcome out;
  out.arms = plan.arms.size();
  const std::string dir = fs::absolute(o.out_dir).string();
  const Ranks ranks;

  // 1. The episode sets; rank 0 holds DIR's lock from its first preparation to the end.
  std::optional<core::FileLock> lock;
  EpisodeSets sets = SimulateEpisodeSets(base, plan, o, dir, ranks, lock);

  // 2. The trainings; a reuse arm starts once its encoders exist.
  ProcessFarm farm = TrainingFarm(base, plan, o, dir, sets);
  const std::size_t done_before = ranks.coordinator ? ArmsDone(plan, dir) : 0;
  const auto log_so_far = [&](const std::string& ended) {  // counts the model folders
    LogInvocation(dir, invocation.started_utc, invocation.WallS(), o.jobs,
                  ArmsDone(plan, dir) - done_before, ended);
  };
  if (ranks.coordinator) {
    log_so_far("killed");
    farm.ended = [&](std::size_t, int) { log_so_far("killed"); };
  }
  FarmOptions fo;
  fo.jobs = o.jobs;
  fo.quiet = o.quiet;
  fo.label = "reproduce " + base.name;
  try {
    RunTrainings(plan, dir, farm, fo, ranks, out);
  } catch (const core::Interrupted&) {
    if (ranks.coordinator) log_so_far("interrupted");  // the farm's counts are lost with it
    if (ranks.world) {
      std::cerr << "uavsim: interrupted; finished trainings are kept\n";
      ranks.world->abort(130);
    }
    throw;
  }
  if (!ranks.coordinator) {
    out.mpi_worker = true;
    return out;
  }
  out.failed = std::max(out.failed, plan.arms.size() - ArmsDone(plan, dir));
  if (out.failed > 0) {
    out.wall_s = invocation.WallS();
    LogInvocation(dir, invocation.started_utc, out.wall_s, o.jobs, out.ran, "failed");
    return out;
  }

  // 3. Every artefact and the report.
  Report(base, plan, o, dir, invocation, out);
  return out;
}

}  // namespace uavsim::sim
