// Writes a finished run's directory (DESIGN.md's output contract):
// truth.csv, estimates.csv, rate_snr.csv and its plot, metrics.json and
// manifest.json, then commits the directory (all-or-nothing: nothing
// appears under the final name before Commit).
#pragma once

#include <map>
#include <string>

#include "results/csv.h"
#include "results/run_directory.h"
#include "sim/edge_server.h"
#include "sim/run.h"
#include "sim/scenario.h"
#include "sim/sensing_node.h"
#include "sim/window_scorer.h"

namespace uavsim::sim {

// What a finished run hands to the writer.
struct FinishedRun {
  const Scenario& scenario;
  const RunOptions& options;
  RunSummary summary;  // filled in before WriteRunMetrics
  std::string started_utc;
  const results::CsvTable& truth;
  const WindowScorer& scores;
  const EdgeServer& edge;
  const WorldModel& world;
  std::map<std::string, NodeTraffic> traffic;  // per modality: camera, lidar, radar
  core::Json recording = nullptr;  // recording.mcap's counts (McapRecorder::Summary), if recorded
};

// Writes the run's tables into `dir`'s staging folder: truth.csv,
// estimates.csv, packets.csv, world_top.csv and layout.csv (sim/run_map.h),
// rate_snr.csv and rate_snr_common.csv (the same over the windows every
// beam-steering method estimated).
//
// packets.csv: a row per message a node sent, in the order sent:
//   t_capture_s,node,modality,sequence,bytes,window,status,t_arrival_s,latency_s
// window = floor(t_capture / window_s) (the alignment window it belongs to),
// status delivered (on time), late, lost or in_flight (still on the link at
// the end); t_arrival_s and latency_s empty unless it arrived.
void WriteRunTables(results::RunDirectory& dir, const FinishedRun& run);
// Then metrics.json (with the summary's wall times) and manifest.json, the
// report unless options.report is off (results/run_report.h: report.html,
// report/ and rate_snr.png;
// warns on stderr, unless quiet, for each figure gnuplot could not draw),
// and commits the directory. Both throw std::runtime_error for I/O.
void WriteRunMetrics(results::RunDirectory& dir, const FinishedRun& run);

}  // namespace uavsim::sim
