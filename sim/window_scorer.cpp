#include "sim/window_scorer.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/rain_attenuation.h"
#include "pipeline/pipeline_config.h"
#include "pipeline/tracking/assignment.h"

namespace uavsim::sim {
namespace {

channel::DownlinkScorer MakeDownlink(const Scenario& s, std::vector<std::string> steered,
                                     const std::string& stream) {
  const double rain_db_per_km = core::RainSpecificAttenuationDbPerKm(
      s.base_station.carrier_ghz, s.weather.rain_mm_h, core::Polarization::kVertical, 0.0);
  return channel::DownlinkScorer(
      s.base_station, rain_db_per_km, std::move(steered),
      channel::SnrGridDb(s.outputs.snr_db.from, s.outputs.snr_db.to, s.outputs.snr_db.step),
      core::RngStream(s.seed, stream));
}

// An estimate farther than this outside the scenario's bounds is no estimate.
constexpr double kAbsurdBeyondBoundsM = 1000.0;

}  // namespace

pipeline::GospaScore GospaAccumulator::Add(const std::vector<Eigen::Vector3d>& targets_m,
                                           const std::vector<Eigen::Vector3d>& estimates_m,
                                           const pipeline::GospaConfig& config,
                                           const std::vector<std::uint32_t>& labels) {
  const pipeline::GospaScore g = pipeline::Gospa(targets_m, estimates_m, config);
  last_label.resize(targets_m.size(), -1);
  was_assigned.resize(targets_m.size(), false);
  for (std::size_t i = 0; i < targets_m.size(); ++i) {
    const int j = g.estimate_of_truth[i];
    if (j >= 0) {
      const std::int64_t label = labels.empty() ? 0 : labels[static_cast<std::size_t>(j)];
      identity_switches += last_label[i] >= 0 && last_label[i] != label;
      fragmentations += last_label[i] >= 0 && !was_assigned[i];
      last_label[i] = label;
    }
    was_assigned[i] = j >= 0;
  }
  const double ospa = pipeline::Ospa(targets_m, estimates_m, config);
  ospa_sum_sq += ospa * ospa;
  cardinality_error +=
      std::abs(static_cast<double>(estimates_m.size()) - static_cast<double>(targets_m.size()));
  per_target.resize(targets_m.size());
  for (std::size_t i = 0; i < targets_m.size(); ++i)
    if (const int j = g.estimate_of_truth[i]; j >= 0)
      per_target[i].Add(estimates_m[static_cast<std::size_t>(j)] - targets_m[i]);
  sum_sq += g.gospa_m * g.gospa_m;
  localization_m2 += g.localization_m2;
  missed_m2 += g.missed_m2;
  false_m2 += g.false_m2;
  missed += static_cast<std::uint64_t>(g.missed);
  false_targets += static_cast<std::uint64_t>(g.false_targets);
  ++windows;
  return g;
}

namespace {

// estimates.csv's columns: with `track` when sets are scored.
std::vector<std::string> EstimateColumns(bool tracks) {
  if (tracks) return {"t_s", "method", "track", "x_m", "y_m", "z_m"};
  return {"t_s", "method", "x_m", "y_m", "z_m"};
}

bool ScoresSets(const Scenario& s) {
  return TargetIndices(s).size() >= 2 || pipeline::RunsMultiTarget(s.pipeline);
}

// A beam at each position, each target served by the beam the optimal
// assignment by distance gives it (none when there are fewer beams).
channel::MethodBeams BeamsServing(const std::vector<Eigen::Vector3d>& targets_m,
                                  const std::vector<Eigen::Vector3d>& positions_m) {
  channel::MethodBeams b;
  b.positions_m = positions_m;
  b.served_by.assign(targets_m.size(), -1);
  if (positions_m.empty()) return b;
  Eigen::MatrixXd distance(targets_m.size(), positions_m.size());
  for (std::size_t i = 0; i < targets_m.size(); ++i)
    for (std::size_t j = 0; j < positions_m.size(); ++j)
      distance(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
          (targets_m[i] - positions_m[j]).norm();
  b.served_by = pipeline::MinCostAssignment(distance);
  return b;
}

}  // namespace

WindowScorer::WindowScorer(const Scenario& scenario, std::vector<std::string> steered)
    : scenario_(scenario),
      steered_(steered),
      downlink_(MakeDownlink(scenario, steered, "base_station/downlink")),
      downlink_common_(MakeDownlink(scenario, std::move(steered), "base_station/downlink/common")),
      scores_sets_(ScoresSets(scenario)),
      estimates_(EstimateColumns(scores_sets_)) {
  const std::vector<std::size_t> targets = TargetIndices(scenario);
  if (targets.size() < 2) return;
  std::vector<std::string> ids;
  for (std::size_t i : targets) ids.push_back(scenario.uavs[i].id);
  const double rain_db_per_km = core::RainSpecificAttenuationDbPerKm(
      scenario.base_station.carrier_ghz, scenario.weather.rain_mm_h, core::Polarization::kVertical,
      0.0);
  const auto& g = scenario.outputs.snr_db;
  multi_beam_.emplace(scenario.base_station, rain_db_per_km, ids, steered_,
                      channel::SnrGridDb(g.from, g.to, g.step),
                      core::RngStream(scenario.seed, "base_station/downlink/targets"));
}

// The box of the nodes, the base station and the target's whole path
// (its closed form, sampled every 0.25 s), grown by a kilometre.
void WindowScorer::FindBounds(const WorldModel& world) {
  lo_m_ = hi_m_ = scenario_.base_station.position_m;
  const auto add = [&](const Eigen::Vector3d& p) {
    lo_m_ = lo_m_.cwiseMin(p);
    hi_m_ = hi_m_.cwiseMax(p);
  };
  for (const NodeConfig& n : scenario_.nodes) add(n.sensor.pose().position_m);
  const double d = scenario_.duration_s;
  for (double t = 0.0;; t = std::min(d, t + 0.25)) {
    add(world.target().StateAt(t).position_m);
    if (t >= d) break;
  }
  lo_m_.array() -= kAbsurdBeyondBoundsM;
  hi_m_.array() += kAbsurdBeyondBoundsM;
  bounded_ = true;
}

std::map<std::string, Eigen::Vector3d> WindowScorer::Score(
    double t_s, const Eigen::Vector3d& truth_m,
    const std::map<std::string, Eigen::Vector3d>& raw_estimates, WorldModel& world,
    const std::vector<Eigen::Vector3d>& targets_m,
    const std::map<std::string, std::vector<pipeline::TrackEstimate>>& tracks) {
  if (!bounded_) FindBounds(world);
  ++windows_;
  std::map<std::string, Eigen::Vector3d> estimated;
  for (const auto& [method, p] : raw_estimates) {
    if (Sane(p))
      estimated.emplace(method, p);
    else
      ++rejected_[method];
  }
  // Each method's set: its sane tracks, or its one estimate.
  std::map<std::string, std::pair<std::vector<Eigen::Vector3d>, std::vector<std::uint32_t>>> sets;
  for (const auto& [method, p] : estimated) {
    rmse_[method].Add(p - truth_m);
    if (tracks.count(method)) continue;
    AddEstimateRow(t_s, method, p, 0);
    sets[method] = {{p}, {0}};
  }
  for (const auto& [method, labelled] : tracks) {
    auto& [set, labels] = sets[method];
    for (const pipeline::TrackEstimate& e : labelled) {
      if (!Sane(e.position_m)) continue;
      AddEstimateRow(t_s, method, e.position_m, e.track);
      set.push_back(e.position_m);
      labels.push_back(e.track);
    }
  }
  if (scores_sets_) {
    const pipeline::GospaConfig config{scenario_.outputs.gospa_c_m, 2.0};
    for (const std::string& method : scenario_.pipeline.methods) {
      const auto it = sets.find(method);
      const pipeline::GospaScore g =
          it == sets.end()
              ? gospa_[method].Add(targets_m, {}, config)
              : gospa_[method].Add(targets_m, it->second.first, config, it->second.second);
      using results::FormatFixed;
      gospa_windows_.AddRow({FormatFixed(t_s, 6), method, FormatFixed(g.gospa_m, 6),
                             FormatFixed(g.localization_m2, 6), FormatFixed(g.missed_m2, 6),
                             FormatFixed(g.false_m2, 6),
                             std::to_string(it == sets.end() ? 0 : it->second.first.size())});
    }
  }
  const std::size_t methods = scenario_.pipeline.methods.size();
  if (methods >= 2 && estimated.size() == methods)
    for (const auto& [method, p] : estimated) rmse_common_[method].Add(p - truth_m);
  world.scene().SetTime(t_s);
  std::map<std::string, Eigen::Vector3d> steering;  // the ablations steer no beam
  for (const std::string& beam : steered_)
    if (auto it = estimated.find(beam); it != estimated.end()) steering.insert(*it);
  downlink_.AddWindow(truth_m, steering, world);
  if (!steered_.empty() && steering.size() == steered_.size()) {
    downlink_common_.AddWindow(truth_m, steering, world);
    ++downlink_common_windows_;
  }
  if (multi_beam_) {
    std::map<std::string, channel::MethodBeams> beams;
    for (const std::string& beam : steered_)
      if (auto it = sets.find(beam); it != sets.end())
        beams[beam] = BeamsServing(targets_m, it->second.first);
    multi_beam_->AddWindow(targets_m, beams, world);
  }
  return estimated;
}

bool WindowScorer::Sane(const Eigen::Vector3d& p) const {
  return p.allFinite() && (p.array() >= lo_m_.array()).all() && (p.array() <= hi_m_.array()).all();
}

void WindowScorer::AddEstimateRow(double t_s, const std::string& method, const Eigen::Vector3d& p,
                                  std::uint32_t track) {
  using results::FormatFixed;
  std::vector<std::string> row{FormatFixed(t_s, 6), method};
  if (scores_sets_) row.push_back(std::to_string(track));
  for (int i = 0; i < 3; ++i) row.push_back(FormatFixed(p[i], 6));
  estimates_.AddRow(row);
}

std::map<std::string, std::uint64_t> WindowScorer::rejected() const {
  std::map<std::string, std::uint64_t> all = rejected_;
  for (const std::string& method : scenario_.pipeline.methods) all[method];
  return all;
}

std::map<std::string, RmseAccumulator> WindowScorer::rmse() const {
  std::map<std::string, RmseAccumulator> all = rmse_;
  for (const std::string& method : scenario_.pipeline.methods) all[method];
  return all;
}

}  // namespace uavsim::sim
