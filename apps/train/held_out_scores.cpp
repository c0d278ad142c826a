#include "apps/train/held_out_scores.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <utility>

#include "pipeline/anchored/anchor_track.h"
#include "pipeline/anchored/geometric_anchor.h"
#include "pipeline/baselines/ekf.h"
#include "pipeline/edge/te_align.h"
#include "sim/edge_server.h"

namespace uavsim::sim {
namespace {

struct Sums {
  double squared = 0.0;
  std::size_t windows = 0;
  std::map<std::pair<std::size_t, std::int64_t>, double> by_window;  // (episode, k - 1)
  std::map<std::pair<std::size_t, std::int64_t>, pipeline::Evaluation::Positions> positions;
  void Add(std::size_t episode, std::int64_t k, const Eigen::Vector3d& estimate,
           const Eigen::Vector3d& truth, int arrived) {
    const double squared_m2 = (estimate - truth).squaredNorm();
    squared += squared_m2;
    ++windows;
    by_window[{episode, k - 1}] = squared_m2;
    positions[{episode, k - 1}] = {estimate, truth, arrived};
  }
};

// Episode `index`, the modalities `bits` allows: adds each method's squared
// errors over the windows it counts.
void ReplayEpisode(const Scenario& base, const pipeline::Episode& ep, std::size_t index, int bits,
                   Sums& ekf_sums, Sums& track_sums) {
  pipeline::TeAlignConfig align_config;
  align_config.window_s = ep.window_s;
  const pipeline::TeAlign align(align_config);
  const std::unique_ptr<pipeline::Ekf> ekf = MakeEkf(base);
  pipeline::AnchorTrack track(ep.window_s);
  const auto k_count = static_cast<std::int64_t>(ep.window_truth.size());

  // The on-time samples of the allowed modalities, by window (capture order).
  std::vector<std::vector<const pipeline::Sample*>> by_window(static_cast<std::size_t>(k_count));
  for (const pipeline::Sample& s : ep.samples) {
    if (!s.on_time || !(bits & (1 << static_cast<int>(s.modality)))) continue;
    if (s.node >= base.nodes.size())
      throw std::invalid_argument("held-out scores: a sample of node " + std::to_string(s.node) +
                                  ", the scenario has " + std::to_string(base.nodes.size()));
    const std::int64_t k = align.WindowOf(s.t_s);
    if (k >= 1 && k <= k_count) by_window[static_cast<std::size_t>(k - 1)].push_back(&s);
  }

  bool started = false;
  for (std::int64_t k = 1; k <= k_count; ++k) {
    pipeline::WindowAnchors anchors;
    int arrived = 0;  // bit m: Modality m
    const auto& samples = by_window[static_cast<std::size_t>(k - 1)];
    for (const pipeline::Sample* s : samples) {
      arrived |= 1 << static_cast<int>(s->modality);
      const std::string& node = base.nodes[s->node].id;
      pipeline::GeometricAnchor anchor;
      if (s->camera) {
        ekf->Observe(node, *s->camera);
        anchor = pipeline::AnchorOf(*s->camera);
      } else if (s->points) {
        ekf->Observe(node, *s->points);
        anchor = pipeline::AnchorOf(*s->points);
      }
      if (anchor.kind != pipeline::GeometricAnchor::Kind::kNone)
        anchors[static_cast<std::size_t>(s->modality)].push_back(anchor);
    }
    started = started || !samples.empty();
    const std::optional<Eigen::Vector3d> p_ekf = ekf->EstimateAt(k * ep.window_s);
    const std::optional<Eigen::Vector3d> p_track = track.OnWindow(k, anchors);
    if (!started || !ep.Scored(k)) continue;
    const Eigen::Vector3d& truth = ep.window_truth[static_cast<std::size_t>(k - 1)];
    if (p_ekf) ekf_sums.Add(index, k, *p_ekf, truth, arrived);
    if (p_track) track_sums.Add(index, k, *p_track, truth, arrived);
  }
}

}  // namespace

std::map<std::string, pipeline::Evaluation> ScoreClassicalMethods(
    const Scenario& base, const std::vector<pipeline::Episode>& episodes) {
  std::map<std::string, pipeline::Evaluation> out;
  for (int bits = 1; bits <= pipeline::kModalitySubsets; ++bits) {
    Sums ekf, track;
    for (std::size_t i = 0; i < episodes.size(); ++i)
      ReplayEpisode(base, episodes[i], i, bits, ekf, track);
    const std::string key = pipeline::ModalitySubsetName(bits);
    for (const auto& [method, sums] : {std::pair{"ekf", ekf}, std::pair{"anchor_track", track}}) {
      pipeline::Evaluation& ev = out[method];
      ev.windows[key] = sums.windows;
      ev.squared_error_m2[key] = sums.by_window;
      ev.position_m[key] = sums.positions;
      ev.rmse_m[key] = sums.windows > 0 ? std::sqrt(sums.squared / sums.windows)
                                        : std::numeric_limits<double>::quiet_NaN();
    }
  }
  return out;
}

}  // namespace uavsim::sim
