// One run of a scenario: builds the world from the scenario, drives it on the
// event core for duration_s of simulated time, and writes the run directory
// (DESIGN.md: manifest.json, truth.csv, metrics.json, ...) all-or-nothing.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <iosfwd>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/interrupt.h"
#include "core/json_io.h"
#include "pipeline/training/dataset.h"
#include "sim/hosted_method.h"
#include "sim/scenario.h"

namespace uavsim::sim {

class EdgeServer;
class WindowScorer;

// One alignment window as a host stepping the run sees it, once the window
// is scored (its downlink channel realised): what arrived
// (edge.last_arrivals(), when the host asked for them), each method's
// estimate, the truth, the scorer (its downlink's last channel).
struct WindowView {
  std::int64_t k = 1;
  double t_s = 0.0;  // the window's end
  const Eigen::Vector3d* truth_m = nullptr;
  const std::map<std::string, Eigen::Vector3d>* estimated = nullptr;  // as scored
  const EdgeServer* edge = nullptr;
  const WindowScorer* scorer = nullptr;
};

struct RunOptions {
  std::string out_dir;  // final run directory
  bool force = false;   // replace an existing out_dir
  bool quiet = false;   // no progress, no summary
  // Draw report.html and report/ (results/run_report.h, by gnuplot). Sweeps
  // turn it off for their points: `uavsim report` draws a point's report
  // when wanted.
  bool report = true;
  std::vector<std::string> record;  // what to record: camera, lidar, radar, mcap
  std::string scenario_file;        // for the manifest
  // Training-data generation (apps/train/train.h): when set, every node frame whose
  // pre-processing found something is added to *collect with the truth at
  // its capture time and whether it reached the edge in time, and the truth
  // at every window's end; and nothing is written (out_dir is ignored).
  pipeline::Episode* collect = nullptr;
  // Sensing traces (sim/sensing_trace.h): write what the nodes send to
  // trace_dir/<key>.trace when the run completes; take the nodes' frames
  // from replay_dir/<key>.trace instead of sensing (the same outputs, byte
  // for byte; refused with a recording of sensor frames or `collect`).
  std::string trace_dir;
  std::string replay_dir;
  // The Python methods' factories (sim/hosted_method.h; null: none).
  const HostedMethods* hosted = nullptr;
  // Called at every window once it is scored (apps/python's environment
  // waits there for its agent); the edge keeps each window's arrivals for
  // it. Changes no output.
  std::function<void(const WindowView&)> on_window;
};

struct RunSummary {
  double sim_s = 0.0;
  double wall_s = 0.0;  // from the start to the run directory's tables written
  // Wall seconds per part of the run, in the order first measured:
  // "setup", "node/<id>/capture", ".../preprocess", ".../record",
  // ".../encode", "edge/<method>", "beams", "record" (the windows written to
  // recording.mcap), "write", and "other" (the rest of
  // wall_s: the event loop, uplinks, truth, and waiting for frames). Nodes
  // that capture on threads of their own overlap the rest, so the parts sum
  // to wall_s or more.
  std::vector<std::pair<std::string, double>> profile_s;
  std::size_t truth_rows = 0;
  std::map<std::string, std::uint64_t> frames;  // per modality
  // Per method that ran: RMSE over the windows it estimated, or nothing if
  // it never produced an estimate.
  std::map<std::string, std::optional<double>> rmse_m;
  // The same over the windows every method estimated (methods start at
  // different windows: the EKF waits for a confirmed track), when there are
  // two or more methods and such windows.
  std::map<std::string, double> rmse_common_m;
  std::uint64_t common_windows = 0;
};

// Throws core::UsageError (exists, not forced; a trace to replay that is
// missing or does not match), std::runtime_error (I/O) or
// core::Interrupted (SIGINT/SIGTERM during the run); the run directory then does not
// exist under its final name.
RunSummary RunScenario(const Scenario& scenario, const RunOptions& options);

}  // namespace uavsim::sim
