// Geometric anchors: where a node's pre-processing already says the target
// is, in world coordinates, and the edge's bookkeeping of them (an extension
// of the paper, see NOTES.md 2026-11-22 (4)). The learned edge network
// regresses a position to a few centimetres only with help: an anchored
// UAVLoc model picks among these candidate positions (a masked softmax) and
// adds a learned residual, instead of regressing the position from the
// latents alone. Plain C++ (Eigen only): the node, the edge's online step
// and the trainer share it.
//
//   camera  the ray from the left eye through the ROI centre (what the
//           camera knows well: its bearing; 0.1 degree median error)
//   LiDAR   the centroid of the dynamic points
//   radar   the centroid of the kept cluster
//
// The edge holds each modality's latest two anchors across windows and
// offers kAnchorCandidates candidates per window: the LiDAR point and the
// radar point carried forward to the window's end at the velocity of their
// last two fixes (a point held for a second is 6 m behind a drone flying
// 6 m/s; as last seen when the fixes give no plausible velocity), each of
// them moved onto the held camera ray (its nearest point there), and the
// point of the camera ray at each one's range from its own sensor, carried
// forward at its range rate (the camera's bearing with the ranging sensor's
// range: the radar measures range to centimetres but angles to degrees).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <optional>

#include "pipeline/observations.h"

namespace uavsim::pipeline {

struct GeometricAnchor {
  enum class Kind : std::uint8_t { kNone, kPoint, kRay };
  Kind kind = Kind::kNone;
  Eigen::Vector3d origin_w = Eigen::Vector3d::Zero();      // the point, or the ray's origin
  Eigen::Vector3d direction_w = Eigen::Vector3d::UnitX();  // unit; rays only
  // Points only: the sensor's position and the mean range of the points from it.
  Eigen::Vector3d sensor_w = Eigen::Vector3d::Zero();
  double range_m = 0.0;
  double t_s = 0.0;  // capture time of the observation
};

// The camera's ray (kNone when nothing was detected).
GeometricAnchor AnchorOf(const CameraObservation& obs);
// The centroid of the points and their mean range (kNone for an empty cloud).
GeometricAnchor AnchorOf(const PointObservation& obs);

// Bytes an anchor adds to a node's message (float32 values): 16 for a point
// (centroid and mean range; the sensor's position is configuration), 24 for
// a ray (origin and direction; its time is the message's capture stamp).
std::uint32_t AnchorBytes(Modality m);

// Candidates: 0 LiDAR point, 1 radar point, 2 and 3 those projected onto the
// camera ray, 4 and 5 the camera ray at the LiDAR's and the radar's range.
inline constexpr int kAnchorCandidates = 6;
// Per window: each candidate's validity and normalised position (24); the
// age of each modality's held anchor at the window's end (capture to
// deadline), in units of kMaxAge_s and of kFineAge_s, both saturating at 1
// (6); whether it arrived in this window (3); whether the LiDAR and the radar
// point are carried forward (2); the held LiDAR and radar points' distances
// from the camera ray (2); their distance from each other (1); the camera
// ray's direction (3). Modalities in Modality order.
inline constexpr int kAnchorFeatures = 41;

// What the network sees of the anchors in one window. Candidates are in
// normalised coordinates (p - centre) / scale like the network's output.
struct AnchorWindow {
  std::array<Eigen::Vector3d, kAnchorCandidates> candidates = {};
  std::array<float, kAnchorCandidates> valid = {};
  std::array<float, kAnchorFeatures> features = {};
};

class AnchorTracker {
 public:
  // Positions are normalised as (p - centre) / scale, ages in seconds
  // divided by kMaxAge_s. Throws std::invalid_argument for window_s or scale
  // not finite and > 0.
  AnchorTracker(double window_s, const Eigen::Vector3d& centre_m, double scale_m);

  // Window k's anchors (index: Modality; kNone for a modality with nothing in
  // the window). Windows must increase; skipped ones count as empty.
  AnchorWindow Update(std::int64_t k, const std::array<GeometricAnchor, kModalityCount>& arrived);
  void Reset();

  static constexpr double kMaxAge_s = 5.0;  // ages saturate here
  static constexpr double kFineAge_s = 1.0;
  static constexpr double kRayDistanceUnit_m = 5.0;
  // Two fixes give a velocity when they are this far apart in time and the
  // speed is plausible; else the carried-forward candidates are invalid.
  static constexpr double kMinFixGap_s = 0.05;
  static constexpr double kMaxFixGap_s = 2.0;
  static constexpr double kMaxSpeed_mps = 40.0;

 private:
  struct Held {
    std::optional<std::int64_t> window;  // of the latest update
    GeometricAnchor anchor;
    std::optional<GeometricAnchor> previous;  // the update before
  };
  double window_s_;
  Eigen::Vector3d centre_m_;
  double scale_m_;
  std::array<Held, kModalityCount> held_;
};

// The point of the ray (origin o, unit direction d) nearest to p, at least
// 1 m in front of the origin.
Eigen::Vector3d ProjectOntoRay(const Eigen::Vector3d& p, const Eigen::Vector3d& o,
                               const Eigen::Vector3d& d);
// The point of the ray (o, d) at distance `range` from `sensor`: of the two
// crossings of the sphere the one nearer to `hint`; the ray's point nearest
// to the sensor when it misses the sphere; at least 1 m in front of o.
Eigen::Vector3d RangeOnRay(const Eigen::Vector3d& sensor, double range, const Eigen::Vector3d& hint,
                           const Eigen::Vector3d& o, const Eigen::Vector3d& d);

}  // namespace uavsim::pipeline
