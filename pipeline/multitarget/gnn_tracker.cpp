#include "pipeline/multitarget/gnn_tracker.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "pipeline/tracking/assignment.h"

namespace uavsim::pipeline {
namespace {

// chi-square quantiles at 0.99 for 1 to 4 degrees of freedom (the anchor
// filter's gates).
constexpr double kGate[] = {0.0, 6.635, 9.210, 11.345, 13.277};
// A pair the gate refuses, or another track's miss: never chosen, since
// every track's own miss costs at most kGate[4].
constexpr double kRefused = 1e6;

// The gate of a detection: its measurement's degrees of freedom.
double GateOf(const Detection& d) {
  if (d.anchor.kind == GeometricAnchor::Kind::kRay) return kGate[2];
  if (d.modality == core::Modality::kRadar && d.anchor.has_range_rate) return kGate[4];
  return kGate[3];
}

}  // namespace

GnnTracker::GnnTracker(double window_s) : window_s_(window_s) {
  if (!(std::isfinite(window_s) && window_s > 0.0))
    throw std::invalid_argument("GnnTracker: window_s must be finite and > 0, got " +
                                std::to_string(window_s));
}

void GnnTracker::Reset() {
  last_window_.reset();
  tracks_.clear();
  next_label_ = 1;
}

std::optional<Eigen::Vector3d> GnnTracker::PositionAt(const Track& t, double t_s) const {
  const auto e = t.filter.PredictAt(t_s);
  if (!e) return std::nullopt;
  return e->position_m;
}

bool GnnTracker::SameTarget(const Track& a, const Track& b, double t_s) const {
  const auto ea = a.filter.PredictAt(t_s), eb = b.filter.PredictAt(t_s);
  return ea && eb && (ea->position_m - eb->position_m).norm() < kMerge_m &&
         (ea->velocity_mps - eb->velocity_mps).norm() < kMergeSpeed_mps;
}

bool GnnTracker::confirmed(std::uint32_t label) const {
  for (const Track& t : tracks_)
    if (t.label == label) return t.confirmed;
  return false;
}

void GnnTracker::Birth(const Detection& d, std::size_t index) {
  if (d.anchor.kind != GeometricAnchor::Kind::kPoint) return;
  for (const Track& t : tracks_)
    if (t.filter.AssociationCost(d.modality, d.anchor)) return;  // inside a track's gate
  Track t;
  t.label = next_label_++;
  t.born = last_window_.value_or(0) + 1;
  t.filter.StartAt(d.modality, d.anchor);
  t.corroborated = d.modality != core::Modality::kRadar;
  t.hit = true;
  assigned_[t.label].push_back(index);
  tracks_.push_back(std::move(t));
}

void GnnTracker::ApplyScan(const std::vector<const Detection*>& scan, const Detection* first) {
  const auto rows = static_cast<Eigen::Index>(tracks_.size());
  const auto n = static_cast<Eigen::Index>(scan.size());
  std::vector<bool> taken(scan.size(), false);
  if (rows > 0) {
    // Rows: tracks; columns: the detections, then one miss per track.
    Eigen::MatrixXd cost = Eigen::MatrixXd::Constant(rows, n + rows, kRefused);
    for (Eigen::Index i = 0; i < rows; ++i) {
      const Track& t = tracks_[static_cast<std::size_t>(i)];
      for (Eigen::Index j = 0; j < n; ++j) {
        const Detection& d = *scan[static_cast<std::size_t>(j)];
        if (const auto c = t.filter.AssociationCost(d.modality, d.anchor)) cost(i, j) = *c;
      }
      cost(i, n + i) = GateOf(*scan.front());
    }
    const std::vector<int> column = MinCostAssignment(cost);
    for (Eigen::Index i = 0; i < rows; ++i) {
      const int j = column[static_cast<std::size_t>(i)];
      if (j < 0 || j >= n || !(cost(i, j) < kRefused)) continue;
      Track& t = tracks_[static_cast<std::size_t>(i)];
      const Detection& d = *scan[static_cast<std::size_t>(j)];
      taken[static_cast<std::size_t>(j)] = true;
      if (t.filter.UpdateWith(d.modality, d.anchor)) {
        assigned_[t.label].push_back(static_cast<std::size_t>(&d - first));
        if (d.anchor.kind == GeometricAnchor::Kind::kPoint) t.hit = true;
        if (d.modality != core::Modality::kRadar) t.corroborated = true;
      }
    }
  }
  for (std::size_t j = 0; j < scan.size(); ++j)
    if (!taken[j]) Birth(*scan[j], static_cast<std::size_t>(scan[j] - first));
}

void GnnTracker::Manage(std::int64_t k, double t_end_s) {
  for (Track& t : tracks_) {
    t.hits.push_back(t.hit);
    t.hit = false;
    if (static_cast<int>(t.hits.size()) > kConfirmN) t.hits.pop_front();
    if (!t.confirmed && t.corroborated &&
        std::count(t.hits.begin(), t.hits.end(), true) >= kConfirmM)
      t.confirmed = true;
  }
  std::vector<bool> drop(tracks_.size(), false);
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    const Track& t = tracks_[i];
    if (!t.confirmed && k - t.born + 1 >= kTentativeWindows) drop[i] = true;
    if (t.confirmed && t_end_s - t.filter.last_ranging_s() > kMaxCoast_s) drop[i] = true;
  }
  // Two tracks on one target: the tentative one goes, else the younger.
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    if (drop[i]) continue;
    for (std::size_t j = i + 1; j < tracks_.size(); ++j) {
      if (drop[j] || !SameTarget(tracks_[i], tracks_[j], t_end_s)) continue;
      const bool keep_younger = tracks_[j].confirmed && !tracks_[i].confirmed;
      drop[keep_younger ? i : j] = true;
      if (keep_younger) break;
    }
  }
  std::vector<Track> kept;
  for (std::size_t i = 0; i < tracks_.size(); ++i)
    if (!drop[i]) kept.push_back(std::move(tracks_[i]));
  tracks_ = std::move(kept);
}

std::vector<TrackEstimate> GnnTracker::OnWindow(std::int64_t k,
                                                const std::vector<Detection>& detections) {
  if (last_window_ && k <= *last_window_)
    throw std::invalid_argument("GnnTracker::OnWindow: window " + std::to_string(k) +
                                " is not after " + std::to_string(*last_window_));
  if (last_window_)
    for (std::int64_t skipped = *last_window_ + 1; skipped < k; ++skipped) {
      last_window_ = skipped;
      Manage(skipped, static_cast<double>(skipped) * window_s_);
    }
  assigned_.clear();
  // Scans: one node's detections of one capture, in capture order (ties:
  // node order, then the order they came in).
  std::vector<const Detection*> ordered;
  for (const Detection& d : detections)
    if (d.anchor.kind != GeometricAnchor::Kind::kNone) ordered.push_back(&d);
  std::stable_sort(ordered.begin(), ordered.end(), [](const Detection* a, const Detection* b) {
    if (a->t_capture_s != b->t_capture_s) return a->t_capture_s < b->t_capture_s;
    return a->node < b->node;
  });
  for (std::size_t begin = 0; begin < ordered.size();) {
    std::size_t end = begin + 1;
    while (end < ordered.size() && ordered[end]->node == ordered[begin]->node &&
           ordered[end]->t_capture_s == ordered[begin]->t_capture_s)
      ++end;
    ApplyScan({ordered.begin() + static_cast<std::ptrdiff_t>(begin),
               ordered.begin() + static_cast<std::ptrdiff_t>(end)},
              detections.data());
    begin = end;
  }
  const double t_end_s = static_cast<double>(k) * window_s_;
  last_window_ = k;
  Manage(k, t_end_s);
  // The live tracks (deleted ones out, every live one in).
  std::map<std::uint32_t, std::vector<std::size_t>> live;
  for (const Track& t : tracks_) live[t.label] = std::move(assigned_[t.label]);
  assigned_ = std::move(live);
  std::vector<TrackEstimate> out;
  for (const Track& t : tracks_)
    if (t.confirmed)
      if (const auto p = PositionAt(t, t_end_s)) out.push_back({t.label, *p});
  return out;
}

}  // namespace uavsim::pipeline
