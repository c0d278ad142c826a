#include "sim/run.h"

#include <chrono>
#include <csignal>
#include <ctime>
#include <memory>

#include "results/csv.h"
#include "results/run_directory.h"
#include "sim/core/periodic_process.h"
#include "sim/core/progress.h"
#include "sim/core/rng.h"
#include "sim/core/simulator.h"
#include "sim/core/time.h"
#include "sim/version.h"

namespace uavsim::sim {
namespace {

volatile std::sig_atomic_t g_interrupt = 0;

extern "C" void OnSignal(int) { g_interrupt = 1; }

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

}  // namespace

void InstallInterruptHandlers() {
  struct sigaction sa {};
  sa.sa_handler = OnSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

RunSummary RunScenario(const Scenario& s, const RunOptions& o) {
  if (!o.record.empty())
    throw core::UsageError("uavsim run: --record " + o.record.front() +
                           ": not available yet (recording arrives with the sensor models)");
  const auto wall_start = std::chrono::steady_clock::now();
  const std::string started_utc = UtcNow();
  results::RunDirectory dir(o.out_dir, o.force);

  core::Simulator sim;
  const core::SimTime t_end = core::Seconds(s.duration_s);

  // Ground truth of the target, sampled on its own timer.
  const auto target =
      core::MakeTrajectory(s.uavs.front().trajectory,
                           core::RngStream(s.seed, "uav/" + s.uavs.front().id + "/trajectory"));
  results::CsvTable truth({"t_s", "x_m", "y_m", "z_m", "vx_mps", "vy_mps", "vz_mps"});
  core::PeriodicProcess truth_timer(
      s.outputs.truth_rate_hz, 0.0, 0.0, core::RngStream(s.seed, "truth"),
      [&](std::int64_t, core::SimTime t) {
        const auto x = target->StateAt(core::ToSeconds(t));
        using results::FormatFixed;
        truth.AddRow({FormatFixed(core::ToSeconds(t), 6), FormatFixed(x.position_m.x(), 6),
                      FormatFixed(x.position_m.y(), 6), FormatFixed(x.position_m.z(), 6),
                      FormatFixed(x.velocity_mps.x(), 6), FormatFixed(x.velocity_mps.y(), 6),
                      FormatFixed(x.velocity_mps.z(), 6)});
      });
  truth_timer.Start(sim, 0, t_end);

  // Frame timers of every sensing node, each with its own clock stream. The
  // sensor models hang their captures on these ticks as they land.
  std::map<std::string, std::uint64_t> frames;
  std::map<std::string, std::uint64_t> raw_bytes;
  for (const char* m : {"camera", "lidar", "radar"}) frames[m] = 0, raw_bytes[m] = 0;
  std::vector<std::unique_ptr<core::PeriodicProcess>> frame_timers;
  for (const NodeConfig& node : s.nodes) {
    const auto& timing = node.sensor.timing();
    const std::string modality = node.sensor.modality();
    const auto bytes = static_cast<std::uint64_t>(node.sensor.RawBytesPerFrame());
    frame_timers.push_back(std::make_unique<core::PeriodicProcess>(
        timing.rate_hz, timing.phase_s, timing.clock_jitter_s,
        core::RngStream(s.seed, "node/" + node.id + "/clock"),
        [&frames, &raw_bytes, modality, bytes](std::int64_t, core::SimTime) {
          ++frames[modality];
          raw_bytes[modality] += bytes;
        }));
    frame_timers.back()->Start(sim, 0, t_end);
  }

  // Once per simulated second: progress, and a look for termination signals.
  core::Progress progress("run " + s.name, s.duration_s, "sim s", o.quiet);
  bool interrupted = false;
  core::PeriodicProcess housekeeping(1.0, 0.0, 0.0, core::RngStream(s.seed, "housekeeping"),
                                     [&](std::int64_t, core::SimTime t) {
                                       progress.Update(core::ToSeconds(t));
                                       if (g_interrupt) interrupted = true, sim.Stop();
                                     });
  housekeeping.Start(sim, 0, t_end);

  sim.RunUntil(t_end);
  if (interrupted || g_interrupt) throw Interrupted();
  progress.Finish();

  RunSummary summary;
  summary.sim_s = s.duration_s;
  summary.truth_rows = truth.rows();
  summary.frames = frames;
  summary.wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();

  dir.WriteText("truth.csv", truth.str());

  core::Json metrics = core::Json::object();
  metrics["rmse_m"] = core::Json::object();  // filled as localization methods land
  core::Json modalities = core::Json::object();
  for (const auto& [m, n] : frames) modalities[m] = {{"frames", n}};
  metrics["modalities"] = modalities;
  metrics["sim_s"] = summary.sim_s;
  metrics["wall_s"] = summary.wall_s;
  metrics["realtime_factor"] = summary.wall_s > 0 ? summary.sim_s / summary.wall_s : 0.0;
  dir.WriteJson("metrics.json", metrics);

  core::Json manifest = core::Json::object();
  manifest["uavsim_version"] = Version();
  manifest["git_hash"] = GitHash();
  manifest["scenario_file"] = o.scenario_file;
  manifest["seed"] = s.seed;
  manifest["started_utc"] = started_utc;
  manifest["wall_s"] = summary.wall_s;
  manifest["scenario"] = ResolvedJson(s);
  dir.WriteJson("manifest.json", manifest);

  dir.Commit();
  return summary;
}

}  // namespace uavsim::sim
