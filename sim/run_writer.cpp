#include "sim/run_writer.h"

#include <algorithm>
#include <filesystem>
#include <iostream>

#include "results/run_report.h"
#include "sim/run_map.h"
#include "sim/version.h"
#include "sim/window_scorer.h"
#include "sim/world_model.h"

namespace uavsim::sim {
namespace {

// metrics.json's "gospa" (several targets, or a multi-target method): per
// method the RMS of GOSPA and of OSPA over the windows, the mean of GOSPA's
// parts and of the cardinality error per window, each target's RMSE where
// assigned, and the identity switches and fragmentations over the run.
core::Json GospaJson(const FinishedRun& run) {
  core::Json methods = core::Json::object();
  const std::vector<std::size_t>& targets = run.world.targets();
  for (const auto& [method, g] : run.scores.gospa()) {
    const double n = static_cast<double>(std::max<std::uint64_t>(g.windows, 1));
    core::Json per_target = core::Json::object();
    for (std::size_t i = 0; i < targets.size(); ++i) {
      const RmseAccumulator none;
      const RmseAccumulator& a = i < g.per_target.size() ? g.per_target[i] : none;
      per_target[run.scenario.uavs[targets[i]].id] = {
          {"rmse_m", a.count ? core::Json(a.value()) : core::Json(nullptr)}, {"windows", a.count}};
    }
    methods[method] = {{"rms_m", g.rms_m()},
                       {"ospa_rms_m", g.ospa_rms_m()},
                       {"cardinality_error", g.cardinality_error / n},
                       {"per_target", per_target},
                       {"localization_m2", g.localization_m2 / n},
                       {"missed_m2", g.missed_m2 / n},
                       {"false_m2", g.false_m2 / n},
                       {"missed_per_window", static_cast<double>(g.missed) / n},
                       {"false_per_window", static_cast<double>(g.false_targets) / n},
                       {"identity_switches", g.identity_switches},
                       {"fragmentations", g.fragmentations}};
  }
  return {{"c_m", run.scenario.outputs.gospa_c_m},
          {"p", 2},
          {"alpha", 2},
          {"targets", run.world.targets().size()},
          {"methods", methods}};
}

// metrics.json: RMSE per method, reception per modality, data rates.
core::Json Metrics(const FinishedRun& run) {
  const RunSummary& summary = run.summary;
  core::Json metrics = core::Json::object();
  // Every method that ran has an entry; null when it never produced an
  // estimate (e.g. a run shorter than the filter's warm-up).
  core::Json rmse_json = core::Json::object();
  core::Json windows_json = core::Json::object();
  for (const auto& [method, acc] : run.scores.rmse()) {
    rmse_json[method] = acc.count ? core::Json(acc.value()) : core::Json(nullptr);
    windows_json[method] = acc.count;
  }
  metrics["rmse_m"] = rmse_json;
  metrics["windows"] = run.scores.windows();
  metrics["estimated_windows"] = windows_json;
  // Estimates not finite or beyond the scenario's bounds by over a
  // kilometre: counted here, not scored (WindowScorer::Score).
  core::Json rejected_json = core::Json::object();
  for (const auto& [method, n] : run.scores.rejected()) rejected_json[method] = n;
  metrics["rejected_estimates"] = rejected_json;
  // Methods compared on the same windows: those every method estimated.
  metrics["common_windows"] = summary.common_windows;
  core::Json common_json = core::Json::object();
  for (const auto& [method, value] : summary.rmse_common_m) common_json[method] = value;
  metrics["rmse_common_m"] = common_json;
  // rate_snr_common.csv's windows: those every beam-steering method estimated.
  metrics["rate_snr_common_windows"] = run.scores.downlink_common_windows();
  if (!run.scores.gospa().empty()) metrics["gospa"] = GospaJson(run);
  if (!run.edge.model_info().is_null()) metrics["uavloc_model"] = run.edge.model_info();
  core::Json modalities = core::Json::object();
  for (const auto& [m, traffic] : run.traffic) modalities[m] = {{"frames", traffic.frames}};
  run.edge.receiver().WriteMetrics(modalities);
  // Simulator ground truth on the point nodes' selection (sim/sensing_node.h TargetSight).
  for (const auto& [m, traffic] : run.traffic)
    if (m != "camera" && traffic.frames > 0)
      modalities[m]["target_sight"] = {{"frames_seeing_target", traffic.target_frames},
                                       {"frames_sent", traffic.sent_frames},
                                       {"sent_holding_target", traffic.sent_on_target},
                                       {"seeing_and_sent", traffic.target_frames_sent}};
  metrics["modalities"] = modalities;
  core::Json rates = core::Json::object();
  const double duration_s = run.scenario.duration_s;
  for (const auto& [m, traffic] : run.traffic)
    rates[m] = {{"raw", traffic.raw_bytes / 1000.0 / duration_s},
                {"preprocessed", traffic.preprocessed_bytes / 1000.0 / duration_s},
                {"compressed", traffic.compressed_bytes / 1000.0 / duration_s}};
  metrics["data_rate_kBps"] = rates;
  if (!run.recording.is_null()) metrics["recording"] = run.recording;
  metrics["sim_s"] = summary.sim_s;
  metrics["wall_s"] = summary.wall_s;
  metrics["realtime_factor"] = summary.wall_s > 0 ? summary.sim_s / summary.wall_s : 0.0;
  // Where the wall time went (not deterministic, as wall_s); see
  // RunSummary::profile_s.
  core::Json profile = core::Json::object();
  for (const auto& [part, seconds] : summary.profile_s) profile[part] = seconds;
  metrics["profile_s"] = profile;
  return metrics;
}

results::CsvTable PacketsTable(const FinishedRun& run) {
  results::CsvTable t({"t_capture_s", "node", "modality", "sequence", "bytes", "window", "status",
                       "t_arrival_s", "latency_s"});
  const core::SimTime window_ns = core::Seconds(run.scenario.pipeline.window_s);
  for (const channel::MessageRecord& m : run.edge.receiver().log()) {
    const bool arrived = m.t_arrival_ns >= 0;
    t.AddRow(
        {results::FormatFixed(core::ToSeconds(m.t_capture_ns), 6),
         m.node < run.scenario.nodes.size() ? run.scenario.nodes[m.node].id
                                            : std::to_string(m.node),
         core::ModalityName(m.modality), std::to_string(m.sequence),
         std::to_string(m.payload_bytes), std::to_string(m.t_capture_ns / window_ns),
         channel::FateName(m.fate),
         arrived ? results::FormatFixed(core::ToSeconds(m.t_arrival_ns), 6) : "",
         arrived ? results::FormatFixed(core::ToSeconds(m.t_arrival_ns - m.t_capture_ns), 6) : ""});
  }
  return t;
}

core::Json Manifest(const FinishedRun& run) {
  core::Json manifest = core::Json::object();
  manifest["uavsim_version"] = Version();
  manifest["git_hash"] = GitHash();
  manifest["scenario_file"] = run.options.scenario_file;
  manifest["seed"] = run.scenario.seed;
  manifest["started_utc"] = run.started_utc;
  manifest["wall_s"] = run.summary.wall_s;
  manifest["node_extensions"] = pipeline::NodeExtensions(run.scenario.pipeline.preprocess);
  manifest["oracles"] = pipeline::NodeOracles(run.scenario.pipeline.preprocess);
  manifest["scenario"] = ResolvedJson(run.scenario);
  return manifest;
}

}  // namespace

void WriteRunTables(results::RunDirectory& dir, const FinishedRun& run) {
  dir.WriteText("truth.csv", run.truth.str());
  dir.WriteText("estimates.csv", run.scores.estimates().str());
  dir.WriteText("packets.csv", PacketsTable(run).str());
  dir.WriteText("world_top.csv", WorldTopTable(run.scenario, run.world).str());
  dir.WriteText("layout.csv", LayoutTable(run.scenario, run.world).str());
  dir.WriteText("rate_snr.csv", run.scores.downlink().rates().Csv());
  dir.WriteText("rate_snr_common.csv", run.scores.downlink_common().rates().Csv());
  if (run.scores.scores_sets()) dir.WriteText("gospa.csv", run.scores.gospa_windows().str());
  if (const channel::MultiBeamScorer* m = run.scores.multi_beam())
    dir.WriteText("rate_snr_targets.csv", m->Csv());
}

void WriteRunMetrics(results::RunDirectory& dir, const FinishedRun& run) {
  dir.WriteJson("metrics.json", Metrics(run));
  dir.WriteJson("manifest.json", Manifest(run));
  if (run.options.report) {
    const std::string staging = std::filesystem::path(dir.StagingPath("report.html")).parent_path();
    for (const std::string& warning : results::WriteRunReport(staging))
      if (!run.options.quiet) std::cerr << "uavsim: warning: report: " << warning << "\n";
  }
  dir.Commit();
}

}  // namespace uavsim::sim
