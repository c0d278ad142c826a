#include "sim/window_scorer.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/rain_attenuation.h"

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

void GospaAccumulator::Add(const std::vector<Eigen::Vector3d>& targets_m,
                           const std::vector<Eigen::Vector3d>& estimates_m,
                           const pipeline::GospaConfig& config) {
  const pipeline::GospaScore g = pipeline::Gospa(targets_m, estimates_m, config);
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
}

WindowScorer::WindowScorer(const Scenario& scenario, std::vector<std::string> steered)
    : scenario_(scenario),
      steered_(steered),
      downlink_(MakeDownlink(scenario, steered, "base_station/downlink")),
      downlink_common_(MakeDownlink(scenario, std::move(steered), "base_station/downlink/common")) {
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
    const std::vector<Eigen::Vector3d>& targets_m) {
  if (!bounded_) FindBounds(world);
  ++windows_;
  std::map<std::string, Eigen::Vector3d> estimated;
  for (const auto& [method, p] : raw_estimates) {
    const bool sane =
        p.allFinite() && (p.array() >= lo_m_.array()).all() && (p.array() <= hi_m_.array()).all();
    if (sane)
      estimated.emplace(method, p);
    else
      ++rejected_[method];
  }
  for (const auto& [method, p] : estimated) {
    using results::FormatFixed;
    estimates_.AddRow({FormatFixed(t_s, 6), method, FormatFixed(p.x(), 6), FormatFixed(p.y(), 6),
                       FormatFixed(p.z(), 6)});
    rmse_[method].Add(p - truth_m);
  }
  if (targets_m.size() >= 2) {
    const pipeline::GospaConfig config{scenario_.outputs.gospa_c_m, 2.0};
    for (const std::string& method : scenario_.pipeline.methods) {
      std::vector<Eigen::Vector3d> set;
      if (auto it = estimated.find(method); it != estimated.end()) set.push_back(it->second);
      gospa_[method].Add(targets_m, set, config);
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
  return estimated;
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
