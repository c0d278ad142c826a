#include "sim/run.h"

#include <chrono>
#include <ctime>
#include <map>
#include <memory>
#include <optional>
#include <set>

#include "channel/uplink.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "core/periodic_process.h"
#include "core/progress.h"
#include "core/rng.h"
#include "core/simulator.h"
#include "core/time.h"
#include "core/wall_profile.h"
#include "results/csv.h"
#include "results/run_directory.h"
#include "sim/edge_server.h"
#include "sim/recorder.h"
#include "sim/run_writer.h"
#include "sim/sensing_node.h"
#include "sim/sensing_trace.h"
#include "sim/training_collector.h"
#include "sim/window_scorer.h"
#include "sim/world_model.h"

namespace uavsim::sim {
namespace {

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

const char* const kModalities[] = {"camera", "lidar", "radar"};

// The targets' ground truth (truth.csv), sampled on its own timer; no rows
// when `keep` is false (training-data collection). With several targets
// (UavConfig::role) a `target` column names each row's UAV, the targets in
// scenario order at each time; with one the file has no such column.
class TruthSampler {
 public:
  TruthSampler(const Scenario& s, const WorldModel& world, bool keep)
      : table_(Header(world.targets().size() > 1)),
        timer_(s.outputs.truth_rate_hz, 0.0,
               [this, &s, &world, keep](std::int64_t, core::SimTime t) {
                 if (!keep) return;
                 const double t_s = core::ToSeconds(t);
                 if (world.targets().size() == 1) return AddRow(world.target().StateAt(t_s), t);
                 for (std::size_t i : world.targets())
                   AddRow(world.uav(i).StateAt(t_s), t, &s.uavs[i].id);
               }) {}
  void Start(core::Simulator& sim, core::SimTime t_end) { timer_.Start(sim, 0, t_end); }
  const results::CsvTable& table() const { return table_; }

 private:
  static std::vector<std::string> Header(bool targets) {
    std::vector<std::string> h{"t_s", "x_m", "y_m", "z_m", "vx_mps", "vy_mps", "vz_mps"};
    if (targets) h.insert(h.begin() + 1, "target");
    return h;
  }
  void AddRow(const core::KinematicState& x, core::SimTime t, const std::string* target = nullptr) {
    using results::FormatFixed;
    std::vector<std::string> row{
        FormatFixed(core::ToSeconds(t), 6), FormatFixed(x.position_m.x(), 6),
        FormatFixed(x.position_m.y(), 6),   FormatFixed(x.position_m.z(), 6),
        FormatFixed(x.velocity_mps.x(), 6), FormatFixed(x.velocity_mps.y(), 6),
        FormatFixed(x.velocity_mps.z(), 6)};
    if (target) row.insert(row.begin() + 1, *target);
    table_.AddRow(row);
  }
  results::CsvTable table_;
  core::PeriodicProcess timer_;
};

using Uplinks = std::map<std::string, std::unique_ptr<channel::Uplink>>;

// One uplink per entry of /links, shared by the nodes that name it; what
// arrives or is lost goes to the edge server (and to the collector).
Uplinks MakeUplinks(core::Simulator& sim, const Scenario& s, EdgeServer& edge,
                    TrainingCollector* collector) {
  std::vector<std::string> node_ids;
  for (const NodeConfig& n : s.nodes) node_ids.push_back(n.id);
  Uplinks links;
  for (const auto& [name, config] : s.links) {
    auto link = std::make_unique<channel::Uplink>(
        sim, config, s.weather, core::RngStream(s.seed, "link/" + name), node_ids);
    link->SetArrivalCallback([&edge, collector](const channel::Message& m, core::SimTime t) {
      const bool on_time = edge.OnArrival(m, t);
      if (collector && m.content) collector->OnArrival(ContentOf(m), core::ToSeconds(t), on_time);
    });
    link->SetLossCallback([&edge, collector](const channel::Message& m, channel::LossCause) {
      edge.OnLost(m);
      if (collector && m.content) collector->OnLost(ContentOf(m));
    });
    links.emplace(name, std::move(link));
  }
  return links;
}

// The sensing nodes in scenario order, each wired to its uplink, the edge's
// accounting and encoder, and the collector; their frame clocks started.
std::vector<std::unique_ptr<SensingNode>> StartNodes(
    core::Simulator& sim, core::SimTime t_end, const Scenario& s, WorldModel& world,
    Recorder* recorder, EdgeServer& edge, const Uplinks& links, TrainingCollector* collector,
    core::WallProfile* profile, SensingTraceWriter* trace, SensingTraceReader* replay) {
  std::vector<std::unique_ptr<SensingNode>> nodes;
  for (std::size_t i = 0; i < s.nodes.size(); ++i) {
    const NodeConfig& config = s.nodes[i];
    const core::Modality modality = *core::ModalityFromName(config.sensor.modality());
    SensingNode::Wiring wiring;
    wiring.link = links.at(config.uplink).get();
    wiring.receiver = &edge.receiver();
    wiring.encoder = edge.encoder(modality);
    wiring.message_bytes = edge.MessageBytes(modality);
    wiring.profile = profile;
    wiring.trace = trace;
    wiring.replay = replay;
    if (collector)
      wiring.observer = [collector](const SensingNode& node, double t_s, NodeContent& content) {
        collector->OnFrame(node, t_s, content);
      };
    // A node that replays a trace senses nothing: it gets no sensor.
    nodes.push_back(std::make_unique<SensingNode>(
        config, static_cast<std::uint32_t>(i),
        replay ? nullptr : MakeNodeSensor(config, s, world, recorder, profile), s,
        std::move(wiring)));
    nodes.back()->Start(sim, t_end);
  }
  return nodes;
}

// Per modality (every one, with or without a node), the nodes' traffic summed.
std::map<std::string, NodeTraffic> TrafficByModality(
    const std::vector<std::unique_ptr<SensingNode>>& nodes) {
  std::map<std::string, NodeTraffic> traffic;
  for (const char* m : kModalities) traffic[m];
  for (const auto& node : nodes) {
    NodeTraffic& t = traffic[node->config().sensor.modality()];
    t.frames += node->traffic().frames;
    t.raw_bytes += node->traffic().raw_bytes;
    t.preprocessed_bytes += node->traffic().preprocessed_bytes;
    t.compressed_bytes += node->traffic().compressed_bytes;
    t.target_frames += node->traffic().target_frames;
    t.sent_frames += node->traffic().sent_frames;
    t.sent_on_target += node->traffic().sent_on_target;
    t.target_frames_sent += node->traffic().target_frames_sent;
  }
  return traffic;
}

RunSummary Summarize(const Scenario& s, const std::map<std::string, NodeTraffic>& traffic,
                     const WindowScorer* scores, std::size_t truth_rows, double wall_s,
                     const core::WallProfile& profile) {
  RunSummary summary;
  summary.sim_s = s.duration_s;
  summary.truth_rows = truth_rows;
  summary.wall_s = wall_s;
  summary.profile_s = profile.parts();
  // What no part measured: the event loop, the uplinks, the truth.
  summary.profile_s.emplace_back("other", std::max(0.0, wall_s - profile.total_s()));
  for (const auto& [m, t] : traffic) summary.frames[m] = t.frames;
  for (const std::string& method : s.pipeline.methods) summary.rmse_m[method] = std::nullopt;
  if (!scores) return summary;
  for (const auto& [method, acc] : scores->rmse())
    summary.rmse_m[method] = acc.count ? std::optional<double>(acc.value()) : std::nullopt;
  for (const auto& [method, acc] : scores->rmse_common()) {
    summary.rmse_common_m[method] = acc.value();
    summary.common_windows = acc.count;
  }
  return summary;
}

}  // namespace

// DESIGN.md's data flow: world -> sensing nodes -> uplinks -> edge server ->
// window scoring (estimates, beams) -> run directory. Collecting training
// data (o.collect) runs the same world, nodes and uplinks with a collector
// in place of the methods, the scoring and the writer.
RunSummary RunScenario(const Scenario& s, const RunOptions& o) {
  const auto wall_start = std::chrono::steady_clock::now();
  const auto wall_since_start = [wall_start] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  };
  if (!o.replay_dir.empty() && (o.collect || !o.record.empty()))
    throw core::UsageError(
        "a run that replays a sensing trace records nothing (the trace holds no sensor frames)");
  core::WallProfile profile;
  const std::string started_utc = UtcNow();
  std::optional<results::RunDirectory> dir;
  if (!o.collect) dir.emplace(o.out_dir, o.force);

  WorldModel world(s);
  std::optional<Recorder> recorder;
  if (!o.collect)
    recorder.emplace(*dir, std::set<std::string>(o.record.begin(), o.record.end()), s, world);
  core::Simulator sim;
  const core::SimTime t_end = core::Seconds(s.duration_s);
  TruthSampler truth(s, world, !o.collect);
  truth.Start(sim, t_end);

  EdgeServer edge(s, o.scenario_file, o.quiet, /*methods=*/!o.collect, o.hosted);
  edge.set_profile(&profile);
  edge.set_keep_arrivals(static_cast<bool>(o.on_window));
  std::optional<TrainingCollector> collector;
  if (o.collect) collector.emplace(*o.collect, world, s.pipeline.window_s, t_end);
  TrainingCollector* const collecting = collector ? &*collector : nullptr;
  const Uplinks links = MakeUplinks(sim, s, edge, collecting);
  std::optional<SensingTraceWriter> trace;
  std::optional<SensingTraceReader> replay;
  if (!o.trace_dir.empty() || !o.replay_dir.empty()) {
    const std::string key = SensingKey(s, edge.encoder_fingerprint());
    if (!o.trace_dir.empty()) trace.emplace(key, s);
    if (!o.replay_dir.empty()) replay.emplace(o.replay_dir, key, s);
  }
  const auto nodes =
      StartNodes(sim, t_end, s, world, recorder ? &*recorder : nullptr, edge, links, collecting,
                 &profile, trace ? &*trace : nullptr, replay ? &*replay : nullptr);

  // At every alignment window's deadline (its end plus the late allowance)
  // the edge estimates the target's position at the window's end from
  // whatever arrived, and the window is scored.
  std::optional<WindowScorer> scores;
  if (!o.collect) scores.emplace(s, edge.SteeredMethods());
  const core::SimTime allowance = core::Seconds(s.pipeline.late_allowance_s);
  core::PeriodicProcess window_timer(
      1.0 / s.pipeline.window_s, s.pipeline.window_s + s.pipeline.late_allowance_s,
      [&](std::int64_t tick, core::SimTime t_deadline) {
        const core::SimTime t_window_end = t_deadline - allowance;
        const double t_s = core::ToSeconds(t_window_end);
        const Eigen::Vector3d truth_m = world.target().StateAt(t_s).position_m;
        if (collector) return collector->OnWindow(t_window_end, truth_m);
        std::vector<Eigen::Vector3d> targets_m;
        for (std::size_t i : world.targets())
          targets_m.push_back(world.uav(i).StateAt(t_s).position_m);
        const auto estimated = edge.EstimateWindow(tick, t_s);
        std::map<std::string, Eigen::Vector3d> scored;
        {
          const auto timing = core::WallProfile::Measure(&profile, "beams");
          scored = scores->Score(t_s, truth_m, estimated, world, targets_m, edge.last_tracks());
        }
        if (o.on_window) o.on_window({tick + 1, t_s, &truth_m, &scored, &edge, &*scores});
        const auto timing =
            core::WallProfile::Measure(recorder->records_mcap() ? &profile : nullptr, "record");
        recorder->RecordWindow(t_s, world, scored);
      });
  window_timer.Start(sim, 0, t_end + 1);  // a deadline at exactly t_end still runs

  // Once per simulated second: progress, and a look for termination signals.
  core::Progress progress("run " + s.name, s.duration_s, "sim s", o.quiet);
  bool interrupted = false;
  core::PeriodicProcess housekeeping(1.0, 0.0, [&](std::int64_t, core::SimTime t) {
    progress.Update(core::ToSeconds(t));
    if (core::InterruptRequested()) interrupted = true, sim.Stop();
  });
  housekeeping.Start(sim, 0, t_end);

  // Building the world's BVH, loading the model, the nodes' set-up.
  profile.part("setup").seconds += wall_since_start();
  sim.RunUntil(t_end);
  if (interrupted || core::InterruptRequested()) throw core::Interrupted();
  progress.Finish();

  const auto traffic = TrafficByModality(nodes);
  if (trace) trace->Write(o.trace_dir);
  if (o.collect)
    return Summarize(s, traffic, nullptr, truth.table().rows(), wall_since_start(), profile);
  FinishedRun run{s, o, {}, started_utc, truth.table(), *scores, edge, world, traffic, nullptr};
  {
    const auto timing = core::WallProfile::Measure(&profile, "write");
    recorder->Finish(edge.receiver().log());
    run.recording = recorder->McapSummary();
    WriteRunTables(*dir, run);
  }
  run.summary = Summarize(s, traffic, &*scores, truth.table().rows(), wall_since_start(), profile);
  WriteRunMetrics(*dir, run);
  return run.summary;
}

}  // namespace uavsim::sim
