// `mtt`: a classical multi-target tracker over the nodes' detections
// (issue 46; no learning): a track per target, each the anchor filter's
// IMM of a coordinated turn and a constant velocity
// (pipeline/anchored/anchor_filter.h, pipeline/tracking/imm.h), with
// global-nearest-neighbour association (Blackman & Popoli, "Design and
// Analysis of Modern Tracking Systems", 1999, Sec. 6.2) and M-of-N track
// management (ibid., Sec. 3.2).
//
// Each window's detections are grouped into scans (one node's message: its
// observations of one capture) and applied scan by scan in capture order
// (ties: node order), each detection at its own anchor's time. Per scan:
//   gate      every live track predicted to the scan's time; a pair's cost
//             is the innovation's squared Mahalanobis distance d^2, gated
//             at the chi-square 99 % quantile of the measurement's degrees
//             of freedom (ray 2, LiDAR point 3, radar point and radial
//             velocity 4)
//   assign    the optimal assignment (pipeline/tracking/assignment.h) of
//             tracks to detections or to a miss whose cost is the gate:
//             a pair outside the gate is never chosen
//   update    each assigned track with its detection
//   birth     an unassigned LiDAR or radar detection outside every
//             track's gate starts a tentative track (ibid., Sec. 3.2; one
//             inside a gate is a second return of a tracked target, or
//             clutter near it); a camera's ray gives no range: it never
//             starts one
// After each window:
//   confirm   a tentative track with ranging updates in at least M of its
//             last N windows (kConfirmM of kConfirmN) is confirmed once a
//             LiDAR fix or a camera ray has updated it (or started it): a
//             radar alone also sees its multipath ghosts, which move as
//             the target does (chosen on validation seeds, NOTES.md);
//   delete    a tentative track not confirmed kTentativeWindows after its
//             birth, a confirmed one without a ranging update for
//             kMaxCoast_s, and of two tracks closer than kMerge_m whose
//             velocities differ by less than kMergeSpeed_mps (two tracks on
//             one target; targets that cross differ in velocity) the
//             tentative one, else the younger.
// JPDA (Association::kJpda, method `mtt_jpda`; Fortmann, Bar-Shalom &
// Scheffe, "Sonar tracking of multiple targets using joint probabilistic
// data association", IEEE J. Oceanic Engineering 8(3), 1983): a LiDAR or
// radar scan's fixes (as positions: the radar's radial velocity unused) are
// shared among the tracks by their joint association probabilities over
// every feasible event of each cluster of tracks that gate a common fix,
// and each track takes the PDA update of all the fixes it gates
// (AnchorFilter::UpdateWithMixture); a track counts a hit when its fixes'
// probabilities sum to 1/2 or more. Rays, births, confirmation and deletion
// as above.
// It reports the confirmed tracks predicted to the window's end, labelled
// by birth order. Deterministic: no randomness; ties in birth order.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <vector>

#include "pipeline/anchored/anchor_filter.h"
#include "pipeline/multitarget/detection.h"

namespace uavsim::pipeline {

class TargetTracker {
 public:
  // How LiDAR and radar detections are associated (a camera's rays: GNN
  // either way).
  enum class Association { kGnn, kJpda };
  // Throws std::invalid_argument for window_s not finite and > 0.
  explicit TargetTracker(double window_s, Association association = Association::kGnn);

  // Window k (ending at k * window_s) and every detection stamped in it
  // (any order). Windows must increase; skipped ones count as empty.
  // Returns the confirmed tracks at the window's end, by label. Throws
  // std::invalid_argument for k not after the previous window.
  std::vector<TrackEstimate> OnWindow(std::int64_t k, const std::vector<Detection>& detections);
  void Reset();

  // After OnWindow: every live track (tentative ones too), by label, with
  // the indices into that window's detections it took (its birth
  // detection, the ones assigned to it).
  const std::map<std::uint32_t, std::vector<std::size_t>>& assigned() const { return assigned_; }
  // After OnWindow: whether the track is confirmed.
  bool confirmed(std::uint32_t label) const;

  static constexpr int kConfirmM = 3;
  static constexpr int kConfirmN = 5;
  static constexpr int kTentativeWindows = 2 * kConfirmN;
  static constexpr double kMaxCoast_s = AnchorFilter::kMaxCoast_s;
  // JPDA: the probability that a sensor's scan holds a track's target,
  // the false fixes' spatial density, and the events a cluster may have
  // before it falls back to GNN (chosen a priori, not tuned).
  static constexpr double kDetectionProbability = 0.9;
  static constexpr double kClutterPerM3 = 1e-3;
  static constexpr std::size_t kJpdaMaxEvents = 100000;
  static constexpr double kMerge_m = 1.0;
  static constexpr double kMergeSpeed_mps = 1.0;

 private:
  struct Track {
    std::uint32_t label = 0;
    AnchorFilter filter{AnchorFilter::Motion::kImm};
    std::int64_t born = 0;  // window of birth
    std::deque<bool> hits;  // per window since birth, newest last (at most kConfirmN)
    bool hit = false;       // a ranging update in the current window
    bool confirmed = false;
    bool corroborated = false;  // updated by a LiDAR fix or a camera ray
  };

  // `first`: the window's detections (for the indices assigned() keeps).
  void ApplyScan(const std::vector<const Detection*>& scan, const Detection* first);
  void Birth(const Detection& d, std::size_t index);
  // JPDA's scan: the joint association probabilities, then a PDA update
  // of every track (AnchorFilter::UpdateWithMixture).
  void ApplyScanJpda(const std::vector<const Detection*>& scan, const Detection* first);
  // beta[i][j] from each track's gated log-likelihoods of each detection.
  std::vector<std::vector<double>> JointProbabilities(
      const std::vector<std::vector<std::optional<double>>>& log_g) const;
  // Confirms and deletes after window k.
  void Manage(std::int64_t k, double t_end_s);
  // The track's position at t_s (nothing once it no longer predicts).
  std::optional<Eigen::Vector3d> PositionAt(const Track& t, double t_s) const;
  // Whether two tracks follow one target at t_s (see above).
  bool SameTarget(const Track& a, const Track& b, double t_s) const;

  double window_s_;
  Association association_;
  std::optional<std::int64_t> last_window_;
  std::vector<Track> tracks_;  // in birth order
  std::uint32_t next_label_ = 1;
  std::map<std::uint32_t, std::vector<std::size_t>> assigned_;
};

}  // namespace uavsim::pipeline
