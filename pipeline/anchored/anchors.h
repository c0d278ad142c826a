// Geometric anchors: where a node's pre-processing already says the target
// is, in world coordinates, and the edge's bookkeeping of them (an extension
// of the paper; why, in NOTES.md). The learned edge
// network does not regress a position to a few centimetres from latents
// alone: an anchored UAVLoc model picks among these candidate positions (a
// masked softmax, with a free regressed position for windows with no good
// candidate). Plain C++ (Eigen only): the node, the edge's online step
// and the trainer share it.
//
//   camera  the ray from the left eye through the ROI centre (what the
//           camera knows well: its bearing)
//   LiDAR   the centroid of the dynamic points
//   radar   the centroid of the kept cluster
//
// The edge holds each modality's latest two anchors across windows and
// offers kAnchorCandidates candidates per window: the LiDAR point and the
// radar point carried forward to the window's end at the velocity of their
// last two fixes (a point held for a second is 6 m behind a drone flying
// 6 m/s; as last seen when the fixes give no plausible velocity; for at most
// kMaxCarry_s, kMaxCarryOnRay_s for the ray's candidates; none older than
// kMaxAge_s), each of
// them moved onto the held camera ray (its nearest point there), and the
// point of the camera ray at each one's range from its own sensor, carried
// forward at its range rate (the camera's bearing with the ranging sensor's
// range: the radar measures range to centimetres but angles to degrees).
// The four candidates on the ray use only the fixes that agreed with the
// camera's ray when they arrived (a gate: the LiDAR centroid within
// kLidarGate_m of the ray, the radar centroid within kRadarGate_m of the
// ray's point at the radar's range, the ray at most kGateMaxAge_s apart in
// capture time): the node's cluster is often not the drone (rain and fog
// returns, the radar's largest cluster a car); the gate widths were chosen
// on the training episodes (NOTES.md).
// A seventh candidate is the track of an AnchorFilter
// (pipeline/anchored/anchor_filter.h; the IMM of a coordinated turn and a
// constant velocity) fed every anchor of every window: the fixes filtered
// together instead of one carried forward.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "pipeline/anchored/anchor_filter.h"
#include "pipeline/anchored/geometric_anchor.h"

namespace uavsim::pipeline {

// Candidates: 0 LiDAR point, 1 radar point, 2 and 3 those projected onto the
// camera ray, 4 and 5 the camera ray at the LiDAR's and the radar's range, 6
// the AnchorFilter's track.
inline constexpr int kAnchorCandidates = 7;
inline constexpr int kFilterCandidate = 6;
// Per window: candidates 0-5's validity and normalised position (24); the
// age of each modality's held anchor at the window's end (capture to
// deadline), in units of kMaxAge_s and of kFineAge_s, both saturating at 1
// (6); whether it arrived in this window (3); whether the LiDAR and the radar
// point are carried forward (2); the held LiDAR and radar points' distances
// from the camera ray (2); their distance from each other (1); the camera
// ray's direction (3); the gated LiDAR and radar fixes' ages, coarse and
// fine (4), and whether they are carried forward (2); the filter's track:
// validity and normalised position (4), its position's standard deviation
// in kSigmaUnit_m (saturating at 4) and the age of its last ranging update,
// coarse and fine (3). Modalities in Modality order.
inline constexpr int kAnchorFeatures = 54;
inline constexpr int kFilterFeatureOffset = 47;
inline constexpr int kFilterSigmaFeature = kFilterFeatureOffset + 4;

// What the network sees of the anchors in one window. Candidates are in
// normalised coordinates (p - centre) / scale like the network's output.
struct AnchorWindow {
  std::array<Eigen::Vector3d, kAnchorCandidates> candidates = {};
  std::array<float, kAnchorCandidates> valid = {};
  std::array<float, kAnchorFeatures> features = {};
  // The held camera ray for the head's free position: valid, origin
  // (normalised), unit direction.
  std::array<float, 7> ray = {};
};

class AnchorTracker {
 public:
  // Positions are normalised as (p - centre) / scale, ages in seconds
  // divided by kMaxAge_s. Throws std::invalid_argument for window_s or scale
  // not finite and > 0.
  AnchorTracker(double window_s, const Eigen::Vector3d& centre_m, double scale_m);

  // Window k's anchors, every one that arrived stamped in the window: the
  // filter takes them all in capture order, the held anchors each
  // modality's latest. Windows must increase; skipped ones count as empty.
  AnchorWindow Update(std::int64_t k, const WindowAnchors& arrived);
  // The same with at most one anchor per modality (kNone: nothing).
  AnchorWindow Update(std::int64_t k, const std::array<GeometricAnchor, kModalityCount>& arrived);
  void Reset();

  // Ages saturate here, and older anchors give no candidates.
  static constexpr double kMaxAge_s = 5.0;
  static constexpr double kFineAge_s = 1.0;
  static constexpr double kRayDistanceUnit_m = 5.0;
  static constexpr double kSigmaUnit_m = 1.0;
  // Two fixes give a velocity when they are this far apart in time and the
  // speed is plausible; else the point is held as last seen.
  static constexpr double kMinFixGap_s = 0.05;
  static constexpr double kMaxFixGap_s = 2.0;
  static constexpr double kMaxSpeed_mps = 20.0;  // also bounds the range rate
  // A point is carried forward for at most this long, then held; a gated
  // fix, which the candidates then put on the (fresher) ray, for longer.
  static constexpr double kMaxCarry_s = 1.0;
  static constexpr double kMaxCarryOnRay_s = 3.0;
  // The gate of the candidates on the camera's ray (see above).
  static constexpr double kGateMaxAge_s = RayGate::kGateMaxAge_s;
  static constexpr double kLidarGate_m = RayGate::kLidarGate_m;
  static constexpr double kRadarGate_m = RayGate::kRadarGate_m;

 private:
  struct Held {
    std::optional<std::int64_t> window;  // of the latest update
    GeometricAnchor anchor;
    std::optional<GeometricAnchor> previous;  // the update before
    void Take(std::int64_t k, const GeometricAnchor& a);
  };
  // A held point's position and range at t_end: carried forward at the rate
  // of its last two fixes when they give a plausible one (`moving`), else as
  // last seen.
  struct CarriedPoint {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    double range_m = 0.0;
    bool moving = false;
  };
  // Whether each ranging sensor's (LiDAR, radar) held point is carried as moving.
  using Moving = std::array<bool, 2>;

  // Each modality's latest anchor of window k held; the LiDAR's and the
  // radar's also as gated when they agree with the camera's held ray.
  void TakeArrivals(std::int64_t k, const WindowAnchors& all);
  // The ray and the candidates from the held points (all but the filter's).
  void WriteCandidates(double t_end, AnchorWindow& w, Moving& moving, Moving& gated_moving) const;
  // The features of the held and gated points from index f; returns the next index.
  int WriteHeldFeatures(std::int64_t k, double t_end, const Moving& moving,
                        const Moving& gated_moving, AnchorWindow& w, int f) const;
  // The filter's candidate and features from index f; returns the next index.
  int WriteTrackFeatures(double t_end, AnchorWindow& w, int f) const;
  bool Usable(const Held& h, double t_end) const;
  // Capture to t_end, kMaxAge_s for a point never held.
  double Age(const Held& h, double t_end) const;
  Eigen::Vector3d Normalised(const Eigen::Vector3d& p) const;
  void SetCandidate(AnchorWindow& w, int i, bool valid, const Eigen::Vector3d& p_w) const;
  static CarriedPoint Carry(const Held& h, double t_end, double max_carry_s);

  double window_s_;
  Eigen::Vector3d centre_m_;
  double scale_m_;
  std::array<Held, kModalityCount> held_;
  std::array<Held, 2> gated_;  // LiDAR, radar: the fixes that passed the gate
  AnchorFilter filter_{AnchorFilter::Motion::kImm};
};

// The offset of each candidate from the target's reference point, in
// metres: per axis, the median of candidate - truth over the windows in
// which the candidate is valid and within radius_m of the truth; zero for a
// candidate with fewer than min_windows such windows. The candidates locate
// what the sensors see of the target, not its reference point: seen from
// below, the rotor discs' plane (the camera's coverage centroid, the LiDAR's
// hits), and the radar's nearest scatterer. windows[i]'s candidates and
// truth[i] are normalised by scale_m. Throws std::invalid_argument for sizes that differ
// or scale_m, radius_m not finite and > 0.
std::array<Eigen::Vector3d, kAnchorCandidates> MedianCandidateOffsets(
    const std::vector<AnchorWindow>& windows, const std::vector<Eigen::Vector3d>& truth,
    double scale_m, double radius_m, std::size_t min_windows);

}  // namespace uavsim::pipeline
