#include "sim/run_writer.h"

#include <iostream>

#include "results/plot.h"
#include "sim/version.h"

namespace uavsim::sim {
namespace {

void PlotRateSnr(results::RunDirectory& dir, const FinishedRun& run) {
  results::PlotSpec plot;
  plot.title = "Achievable rate vs SNR (" + run.scenario.name + ")";
  plot.x_label = "SNR (dB)";
  plot.y_label = "Rate (bit/s/Hz)";
  plot.x_column = "snr_db";
  plot.y_column = "rate_bps_hz";
  plot.group_column = "beam";
  plot.png_path = dir.StagingPath("rate_snr.png");
  if (const std::string err = results::PlotCsv(dir.StagingPath("rate_snr.csv"), plot);
      !err.empty() && !run.options.quiet)
    std::cerr << "uavsim: warning: rate_snr.png not drawn: " << err << "\n";
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
  // Methods compared on the same windows: those every method estimated.
  metrics["common_windows"] = summary.common_windows;
  core::Json common_json = core::Json::object();
  for (const auto& [method, value] : summary.rmse_common_m) common_json[method] = value;
  metrics["rmse_common_m"] = common_json;
  if (!run.edge.model_info().is_null()) metrics["uavloc_model"] = run.edge.model_info();
  core::Json modalities = core::Json::object();
  for (const auto& [m, traffic] : run.traffic) modalities[m] = {{"frames", traffic.frames}};
  run.edge.receiver().WriteMetrics(modalities);
  metrics["modalities"] = modalities;
  core::Json rates = core::Json::object();
  const double duration_s = run.scenario.duration_s;
  for (const auto& [m, traffic] : run.traffic)
    rates[m] = {{"raw", traffic.raw_bytes / 1000.0 / duration_s},
                {"preprocessed", traffic.preprocessed_bytes / 1000.0 / duration_s},
                {"compressed", traffic.compressed_bytes / 1000.0 / duration_s}};
  metrics["data_rate_kBps"] = rates;
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

core::Json Manifest(const FinishedRun& run) {
  core::Json manifest = core::Json::object();
  manifest["uavsim_version"] = Version();
  manifest["git_hash"] = GitHash();
  manifest["scenario_file"] = run.options.scenario_file;
  manifest["seed"] = run.scenario.seed;
  manifest["started_utc"] = run.started_utc;
  manifest["wall_s"] = run.summary.wall_s;
  manifest["scenario"] = ResolvedJson(run.scenario);
  return manifest;
}

}  // namespace

void WriteRunTables(results::RunDirectory& dir, const FinishedRun& run) {
  dir.WriteText("truth.csv", run.truth.str());
  dir.WriteText("estimates.csv", run.scores.estimates().str());
  dir.WriteText("rate_snr.csv", run.scores.downlink().rates().Csv());
  PlotRateSnr(dir, run);
}

void WriteRunMetrics(results::RunDirectory& dir, const FinishedRun& run) {
  dir.WriteJson("metrics.json", Metrics(run));
  dir.WriteJson("manifest.json", Manifest(run));
  dir.Commit();
}

}  // namespace uavsim::sim
