// A node's geometric anchor: where its pre-processing already says the
// target is, in world coordinates (camera: the ray from the left eye through
// the ROI centre; LiDAR: the centroid of the dynamic points; radar: the
// centroid of the kept cluster), and the geometry the edge does with it. See
// pipeline/anchored/anchors.h for what the edge makes of them. Plain C++ (Eigen only).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "pipeline/node/observations.h"

namespace uavsim::pipeline {

struct GeometricAnchor {
  enum class Kind : std::uint8_t { kNone, kPoint, kRay };
  Kind kind = Kind::kNone;
  Eigen::Vector3d origin_w = Eigen::Vector3d::Zero();      // the point, or the ray's origin
  Eigen::Vector3d direction_w = Eigen::Vector3d::UnitX();  // unit; rays only
  // Points only: the sensor's position and the mean range of the points from it.
  Eigen::Vector3d sensor_w = Eigen::Vector3d::Zero();
  double range_m = 0.0;
  // Radar only (5 channels): the points' mean radial velocity, + receding.
  double range_rate_mps = 0.0;
  bool has_range_rate = false;
  double t_s = 0.0;  // capture time of the observation
};

// The camera's ray (kNone when nothing was detected).
GeometricAnchor AnchorOf(const CameraObservation& obs);
// The centroid of the points and their mean range, and for a radar's cloud
// (5 channels) their mean radial velocity (kNone for an empty cloud).
GeometricAnchor AnchorOf(const PointObservation& obs);

// Bytes an anchor adds to a node's message (float32 values): 16 for a LiDAR
// point (centroid and mean range; the sensor's position is configuration), 20
// for a radar's (and its radial velocity), 24 for a ray (origin and
// direction; its time is the message's capture stamp).
std::uint32_t AnchorBytes(Modality m);

// What arrived in one window: per modality (index: Modality) its anchors in
// capture order.
using WindowAnchors = std::array<std::vector<GeometricAnchor>, kModalityCount>;

// The gate of a LiDAR or radar fix against the camera's ray (the node's
// cluster is often not the drone: rain and fog returns, the radar's largest
// cluster a car): the LiDAR centroid within kLidarGate_m of the ray, the
// radar centroid within kRadarGate_m of the ray's point at the radar's range,
// the two at most kGateMaxAge_s apart in capture time.
struct RayGate {
  static constexpr double kGateMaxAge_s = 0.5;
  static constexpr double kLidarGate_m = 1.5;
  static constexpr double kRadarGate_m = 4.0;
};
bool AnchorAgreesWithRay(Modality m, const GeometricAnchor& point, const GeometricAnchor& ray);

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
