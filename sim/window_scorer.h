// Scores each alignment window of a run (DESIGN.md: pipeline/edge ->
// channel/beam -> results): every method's estimate against the truth at
// the window's end (estimates.csv rows, RMSE over the windows it estimated
// and over the windows every method estimated), and the base station's
// downlink steered at each estimate (rate_snr.csv; channel/beamformer.h). A
// method scores beam gain 0 in windows where it has no estimate yet. A
// second downlink scores only the windows in which every steering method
// has an estimate (rate_snr_common.csv): the methods' curves on the same
// windows, as the RMSE over common windows.
//
// With more than one target (UavConfig::role), or when a multi-target
// method runs (mtt), each method's estimates are also scored as a set
// against every target's truth by GOSPA (pipeline/tracking/gospa.h; c =
// /outputs/gospa_c_m, p = 2, alpha = 2): a multi-target method's labelled
// tracks, another method's one estimate; a window without an estimate
// misses every target. Then estimates.csv has a `track` column: a track's
// label (one row per track), 0 for a method's single estimate.
//
// With several targets the base station also serves every target at once
// (channel/multi_beam.h): a beam per position of each steering method's
// set, each target served by the beam the optimal assignment by distance
// gives it (rate_snr_targets.csv), and "perfect" beams at the true
// positions.
//
// Determinism: the downlinks draw from their own streams
// "base_station/downlink", "base_station/downlink/common" and
// "base_station/downlink/targets".
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "channel/beamformer.h"
#include "channel/multi_beam.h"
#include "pipeline/multitarget/detection.h"
#include "pipeline/tracking/gospa.h"
#include "results/csv.h"
#include "sim/scenario.h"
#include "sim/world_model.h"

namespace uavsim::sim {

// Root mean square of Euclidean errors.
struct RmseAccumulator {
  double sum_sq = 0.0;
  std::size_t count = 0;
  void Add(const Eigen::Vector3d& error) { sum_sq += error.squaredNorm(), ++count; }
  double value() const { return count ? std::sqrt(sum_sq / static_cast<double>(count)) : 0.0; }
};

// A method's GOSPA over the windows, its p-th powers summed; beside it
// OSPA, the cardinality error |estimates - targets| and, per target (in
// scenario order), the RMSE over the windows an estimate was assigned to it.
// Identity (labels: a track's, 0 for a single estimate; Ristic et al.,
// "A metric for performance evaluation of multi-target tracking
// algorithms", IEEE Trans. Signal Processing 59(7), 2011, and the CLEAR MOT
// counts): an identity switch is a target assigned a label other than the
// one it was last assigned; a fragmentation, a target assigned again after
// windows without an assignment.
struct GospaAccumulator {
  double sum_sq = 0.0, localization_m2 = 0.0, missed_m2 = 0.0, false_m2 = 0.0;
  double ospa_sum_sq = 0.0, cardinality_error = 0.0;
  std::uint64_t windows = 0, missed = 0, false_targets = 0;
  std::uint64_t identity_switches = 0, fragmentations = 0;
  std::vector<RmseAccumulator> per_target;
  // Per target: the label last assigned (-1: never) and whether the
  // previous window assigned one.
  std::vector<std::int64_t> last_label;
  std::vector<bool> was_assigned;
  // labels: one per estimate (empty: all 0).
  // Returns the window's score.
  pipeline::GospaScore Add(const std::vector<Eigen::Vector3d>& targets_m,
                           const std::vector<Eigen::Vector3d>& estimates_m,
                           const pipeline::GospaConfig& config,
                           const std::vector<std::uint32_t>& labels = {});
  double rms_m() const { return windows ? std::sqrt(sum_sq / static_cast<double>(windows)) : 0.0; }
  double ospa_rms_m() const {
    return windows ? std::sqrt(ospa_sum_sq / static_cast<double>(windows)) : 0.0;
  }
};

class WindowScorer {
 public:
  // `steered`: the methods whose estimates steer a beam.
  WindowScorer(const Scenario& scenario, std::vector<std::string> steered);

  // One window ending at t_s with the target at truth_m; `estimated`:
  // method -> estimate (world ENU, metres). Poses `world` at t_s for the
  // downlink's blockage and reflections. An estimate that is not finite,
  // or lies more than 1 km outside the box of the nodes, the base station
  // and the target's whole path, counts as no estimate (rejected()).
  // Returns the estimates scored (those not rejected).
  // `targets_m`: every target's truth at t_s (GOSPA is scored with two or
  // more, or with a multi-target method); `tracks`: the multi-target
  // methods' labelled estimates (EdgeServer::last_tracks).
  std::map<std::string, Eigen::Vector3d> Score(
      double t_s, const Eigen::Vector3d& truth_m,
      const std::map<std::string, Eigen::Vector3d>& estimated, WorldModel& world,
      const std::vector<Eigen::Vector3d>& targets_m = {},
      const std::map<std::string, std::vector<pipeline::TrackEstimate>>& tracks = {});

  std::uint64_t windows() const { return windows_; }
  const results::CsvTable& estimates() const { return estimates_; }
  const channel::DownlinkScorer& downlink() const { return downlink_; }
  // Over the windows every steering method estimated (none steering: empty).
  const channel::DownlinkScorer& downlink_common() const { return downlink_common_; }
  std::uint64_t downlink_common_windows() const { return downlink_common_windows_; }
  // Per method that ran (every /pipeline/methods entry, estimated or not).
  std::map<std::string, RmseAccumulator> rmse() const;
  // Per method that ran: the estimates refused as absurd (see Score).
  std::map<std::string, std::uint64_t> rejected() const;
  // Per method over the windows every method estimated (two or more methods).
  const std::map<std::string, RmseAccumulator>& rmse_common() const { return rmse_common_; }
  // With two or more targets (else null).
  const channel::MultiBeamScorer* multi_beam() const {
    return multi_beam_ ? &*multi_beam_ : nullptr;
  }
  // gospa.csv: per window and method its GOSPA and parts (empty unless
  // sets are scored).
  const results::CsvTable& gospa_windows() const { return gospa_windows_; }
  bool scores_sets() const { return scores_sets_; }
  // Per method, with two or more targets or a multi-target method (else empty).
  const std::map<std::string, GospaAccumulator>& gospa() const { return gospa_; }

 private:
  void FindBounds(const WorldModel& world);
  bool Sane(const Eigen::Vector3d& p) const;
  void AddEstimateRow(double t_s, const std::string& method, const Eigen::Vector3d& p,
                      std::uint32_t track);

  const Scenario& scenario_;
  bool bounded_ = false;
  Eigen::Vector3d lo_m_ = Eigen::Vector3d::Zero(), hi_m_ = Eigen::Vector3d::Zero();
  std::map<std::string, std::uint64_t> rejected_;
  std::vector<std::string> steered_;
  channel::DownlinkScorer downlink_;
  channel::DownlinkScorer downlink_common_;
  std::uint64_t downlink_common_windows_ = 0;
  std::optional<channel::MultiBeamScorer> multi_beam_;
  bool scores_sets_;  // GOSPA and the track column
  results::CsvTable estimates_;
  results::CsvTable gospa_windows_{
      {"t_s", "method", "gospa_m", "localization_m2", "missed_m2", "false_m2", "estimates"}};
  std::map<std::string, RmseAccumulator> rmse_, rmse_common_;
  std::map<std::string, GospaAccumulator> gospa_;
  std::uint64_t windows_ = 0;
};

}  // namespace uavsim::sim
