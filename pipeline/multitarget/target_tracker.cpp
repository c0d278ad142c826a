#include "pipeline/multitarget/target_tracker.h"

#include <algorithm>
#include <cmath>
#include <functional>
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

TargetTracker::TargetTracker(double window_s, Association association)
    : window_s_(window_s), association_(association) {
  if (!(std::isfinite(window_s) && window_s > 0.0))
    throw std::invalid_argument("TargetTracker: window_s must be finite and > 0, got " +
                                std::to_string(window_s));
}

void TargetTracker::Reset() {
  last_window_.reset();
  tracks_.clear();
  next_label_ = 1;
}

std::optional<Eigen::Vector3d> TargetTracker::PositionAt(const Track& t, double t_s) const {
  const auto e = t.filter.PredictAt(t_s);
  if (!e) return std::nullopt;
  return e->position_m;
}

bool TargetTracker::SameTarget(const Track& a, const Track& b, double t_s) const {
  const auto ea = a.filter.PredictAt(t_s), eb = b.filter.PredictAt(t_s);
  return ea && eb && (ea->position_m - eb->position_m).norm() < kMerge_m &&
         (ea->velocity_mps - eb->velocity_mps).norm() < kMergeSpeed_mps;
}

bool TargetTracker::confirmed(std::uint32_t label) const {
  for (const Track& t : tracks_)
    if (t.label == label) return t.confirmed;
  return false;
}

void TargetTracker::Birth(const Detection& d, std::size_t index) {
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

void TargetTracker::ApplyScan(const std::vector<const Detection*>& scan, const Detection* first) {
  if (association_ == Association::kJpda && scan.front()->modality != core::Modality::kCamera)
    return ApplyScanJpda(scan, first);
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

// Per cluster of tracks that share gated detections, every feasible joint
// event (each track none or one of its gated detections, each detection at
// most one track), weighted prod (p_D g_ij / lambda) prod (1 - p_D); beta_ij
// the normalised sum over the events that pair them (Fortmann, Bar-Shalom &
// Scheffe 1983). A cluster with more than kJpdaMaxEvents events falls back
// to the GNN assignment of its tracks (beta 1 for each assigned pair).
std::vector<std::vector<double>> TargetTracker::JointProbabilities(
    const std::vector<std::vector<std::optional<double>>>& log_g) const {
  const std::size_t rows = log_g.size(), cols = rows ? log_g.front().size() : 0;
  std::vector<std::vector<double>> beta(rows, std::vector<double>(cols, 0.0));
  // Clusters: tracks linked through a detection both gate.
  std::vector<int> cluster(rows, -1);
  int clusters = 0;
  for (std::size_t i = 0; i < rows; ++i) {
    if (cluster[i] >= 0) continue;
    std::vector<std::size_t> stack{i};
    cluster[i] = clusters;
    while (!stack.empty()) {
      const std::size_t a = stack.back();
      stack.pop_back();
      for (std::size_t j = 0; j < cols; ++j) {
        if (!log_g[a][j]) continue;
        for (std::size_t b = 0; b < rows; ++b)
          if (cluster[b] < 0 && log_g[b][j]) cluster[b] = clusters, stack.push_back(b);
      }
    }
    ++clusters;
  }
  const double log_miss = std::log(1.0 - kDetectionProbability);
  const double log_hit = std::log(kDetectionProbability) - std::log(kClutterPerM3);
  for (int c = 0; c < clusters; ++c) {
    std::vector<std::size_t> members;
    for (std::size_t i = 0; i < rows; ++i)
      if (cluster[i] == c) members.push_back(i);
    // Depth-first over the members' choices; weights relative to the first event's.
    std::vector<int> choice(members.size(), -1);
    std::vector<bool> used(cols, false);
    std::vector<std::vector<double>> sum(members.size(), std::vector<double>(cols, 0.0));
    double total = 0.0;
    std::size_t events = 0;
    bool overflow = false;
    std::function<void(std::size_t, double)> walk = [&](std::size_t k, double log_w) {
      if (overflow) return;
      if (k == members.size()) {
        if (++events > kJpdaMaxEvents) overflow = true;
        const double w = std::exp(log_w);
        total += w;
        for (std::size_t m = 0; m < members.size(); ++m)
          if (choice[m] >= 0) sum[m][static_cast<std::size_t>(choice[m])] += w;
        return;
      }
      choice[k] = -1;
      walk(k + 1, log_w + log_miss);
      for (std::size_t j = 0; j < cols; ++j) {
        const auto& g = log_g[members[k]][j];
        if (!g || used[j]) continue;
        used[j] = true;
        choice[k] = static_cast<int>(j);
        walk(k + 1, log_w + log_hit + *g);
        used[j] = false;
        choice[k] = -1;
      }
    };
    // Shift by the best single pairs to keep exp() in range.
    double shift = 0.0;
    for (std::size_t m = 0; m < members.size(); ++m) {
      double best = log_miss;
      for (std::size_t j = 0; j < cols; ++j)
        if (log_g[members[m]][j]) best = std::max(best, log_hit + *log_g[members[m]][j]);
      shift -= best;
    }
    walk(0, shift);
    if (overflow || !(total > 0.0)) {
      Eigen::MatrixXd cost =
          Eigen::MatrixXd::Constant(static_cast<Eigen::Index>(members.size()),
                                    static_cast<Eigen::Index>(cols + members.size()), kRefused);
      // -2 log g, shifted to be >= 0 (every track is assigned, to a fix or
      // to its own miss, and a miss costs more than any fix: the shift
      // moves every assignment with the most fixes alike).
      double top = 0.0;
      for (std::size_t m = 0; m < members.size(); ++m)
        for (std::size_t j = 0; j < cols; ++j)
          if (log_g[members[m]][j]) top = std::max(top, 2.0 * *log_g[members[m]][j]);
      for (std::size_t m = 0; m < members.size(); ++m) {
        for (std::size_t j = 0; j < cols; ++j)
          if (log_g[members[m]][j])
            cost(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(j)) =
                top - 2.0 * *log_g[members[m]][j];
        cost(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(cols + m)) = kRefused / 2;
      }
      const std::vector<int> column = MinCostAssignment(cost);
      for (std::size_t m = 0; m < members.size(); ++m)
        if (column[m] >= 0 && static_cast<std::size_t>(column[m]) < cols)
          beta[members[m]][static_cast<std::size_t>(column[m])] = 1.0;
      continue;
    }
    for (std::size_t m = 0; m < members.size(); ++m)
      for (std::size_t j = 0; j < cols; ++j) beta[members[m]][j] = sum[m][j] / total;
  }
  return beta;
}

void TargetTracker::ApplyScanJpda(const std::vector<const Detection*>& scan,
                                  const Detection* first) {
  std::vector<AnchorFilter::PositionFix> fixes;
  for (const Detection* d : scan)
    fixes.push_back(AnchorFilter::PositionFixOf(d->modality, d->anchor));
  std::vector<std::vector<std::optional<double>>> log_g(tracks_.size());
  for (std::size_t i = 0; i < tracks_.size(); ++i)
    for (const auto& fix : fixes) log_g[i].push_back(tracks_[i].filter.PositionLogLikelihood(fix));
  const std::vector<std::vector<double>> beta = JointProbabilities(log_g);
  std::vector<bool> gated(scan.size(), false);
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    Track& t = tracks_[i];
    std::vector<AnchorFilter::PositionFix> mine;
    std::vector<double> weights;
    double weight = 0.0;
    for (std::size_t j = 0; j < scan.size(); ++j) {
      if (!log_g[i][j]) continue;
      gated[j] = true;
      mine.push_back(fixes[j]);
      weights.push_back(beta[i][j]);
      weight += beta[i][j];
      if (beta[i][j] >= 0.5)
        assigned_[t.label].push_back(static_cast<std::size_t>(scan[j] - first));
    }
    if (!t.filter.UpdateWithMixture(mine, weights, kDetectionProbability, kClutterPerM3)) continue;
    if (weight >= 0.5) {
      t.hit = true;
      if (scan.front()->modality == core::Modality::kLidar) t.corroborated = true;
    }
  }
  // A detection outside every gate starts a track.
  for (std::size_t j = 0; j < scan.size(); ++j)
    if (!gated[j]) Birth(*scan[j], static_cast<std::size_t>(scan[j] - first));
}

void TargetTracker::Manage(std::int64_t k, double t_end_s) {
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

std::vector<TrackEstimate> TargetTracker::OnWindow(std::int64_t k,
                                                   const std::vector<Detection>& detections) {
  if (last_window_ && k <= *last_window_)
    throw std::invalid_argument("TargetTracker::OnWindow: window " + std::to_string(k) +
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
