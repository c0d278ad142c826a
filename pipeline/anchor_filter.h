// A Kalman filter over the geometric anchors (pipeline/anchors.h): the
// edge's filtered candidate for an anchored UAVLoc model. A LiDAR or radar
// fix carried to the window's deadline on its own is 0.22 m off (median, the
// best of the six single-fix candidates, training episodes) where every fix
// filtered together is 0.13 m off (NOTES.md 2026-11-22 (6)). Uses only what
// the nodes send with their latents: the camera's ray, the LiDAR centroid,
// the radar cluster's centroid, mean range and mean radial velocity.
//
// State, world ENU, SI: x = [p, v, a] (Bar-Shalom, Li & Kirubarajan 2001,
// Secs. 6.2-6.3), per axis
//   constant velocity (white acceleration q_a; a stays 0):
//     F = [1 dt 0; 0 1 0; 0 0 1],  Q = q_a [dt^3/3 dt^2/2 0; dt^2/2 dt 0; 0 0 0]
//   constant acceleration (white jerk q_j; the tracker's: it follows an
//   orbit's turn, which the constant-velocity model lags):
//     F = [1 dt dt^2/2; 0 1 dt; 0 0 1],
//     Q = q_j [dt^5/20 dt^4/8 dt^3/6; dt^4/8 dt^3/3 dt^2/2; dt^3/6 dt^2/2 dt]
// Measurements at their capture times, linear in the state but for the
// radial velocity:
//   ray (o, d)   E^T (p - o) = 0, E = [e1 e2] orthonormal, normal to d;
//                noise per axis (rho sigma_theta)^2 + sigma_ray^2, rho the
//                predicted distance along the ray
//   LiDAR c      p = c, noise sigma_lidar^2 I
//   radar        p = s + R u (u the unit vector from the radar s to the
//                centroid, R the mean range), noise sigma_R^2 u u^T +
//                (R sigma_angle)^2 (I - u u^T): the radar's angles are
//                degrees off, its range centimetres; and its radial velocity
//                rdot = l . v (l the unit vector from s to p), noise
//                sigma_rdot^2, linearised at the prediction
// Each is gated (chi-square, 99 %) against the prediction. A track starts at
// a LiDAR fix that agrees with the latest ray (AnchorAgreesWithRay), put on
// the ray, or at two radar fixes that do and agree with each other; after
// kMaxRejections ranging fixes in a row outside the gate, a LiDAR fix that
// agrees with the ray restarts it. kMaxCoast_s after its last ranging update
// (the rays alone do not fix the range) it coasts: any ranging fix that
// agrees with the ray (radar: confirmed) and not with the track restarts it;
// it predicts until kMaxPredict_s.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <utility>

#include "pipeline/geometric_anchor.h"
#include "pipeline/observations.h"

namespace uavsim::pipeline {

class AnchorFilter {
 public:
  enum class Motion { kCv, kCa };  // constant velocity, constant acceleration
  explicit AnchorFilter(Motion motion = Motion::kCv) : motion_(motion) {}

  struct Estimate {
    Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
    double sigma_m = 0.0;        // sqrt of the position covariance's trace
    double ranging_age_s = 0.0;  // since the last accepted LiDAR or radar fix
  };

  // Anchors of one modality, in capture order across calls (an anchor older
  // than the filter's time is applied at that time). Throws
  // std::invalid_argument for a kind that does not fit the modality.
  void Observe(Modality m, const GeometricAnchor& anchor);
  // The track predicted to t_s (not moved there), nothing before a track
  // has started or kMaxPredict_s after its last ranging update.
  std::optional<Estimate> PredictAt(double t_s) const;
  void Reset() { *this = AnchorFilter(motion_); }
  Motion motion() const { return motion_; }

  // Noises: near the anchors' errors measured on training episodes (ray 2
  // mrad rms, correlated from frame to frame; LiDAR centroid 0.17-0.20 m per
  // axis; radar range 0.06 m, angles 0.03 rad), then the best of a few
  // settings by the track's error on them (NOTES.md 2026-11-22 (6)).
  static constexpr double kAccelPsd = 2.0;              // CV: q, m^2/s^3
  static constexpr double kJerkPsd = 1.0;               // CA: q, m^2/s^5
  static constexpr double kStartAccelSigma_mps2 = 3.0;  // CA: per axis
  static constexpr double kRaySigma_rad = 3e-3;         // sigma_theta
  static constexpr double kRayFloor_m = 0.10;           // sigma_ray: ROI centre vs body
  static constexpr double kLidarSigma_m = 0.15;         // per axis
  static constexpr double kRangeSigma_m = 0.10;         // radar range
  static constexpr double kRadarAngleSigma_rad = 0.03;
  static constexpr double kRangeRateSigma_mps = 0.10;  // radar radial velocity
  static constexpr double kStartSpeedSigma_mps = 6.0;  // per axis, unknown velocity
  // A track that has had no ranging update for this long coasts: any
  // ranging fix that agrees with the ray (a radar's confirmed) restarts it;
  // it predicts for kMaxPredict_s (a candidate whose age the head sees).
  static constexpr double kMaxCoast_s = 2.0;
  static constexpr double kMaxPredict_s = 5.0;
  // Ranging fixes in a row outside the gate before one that agrees with the
  // ray restarts the track.
  static constexpr int kMaxRejections = 3;
  // A second radar fix confirms a first within this distance (plus the
  // distance kMaxSpeed_mps covers in between).
  static constexpr double kConfirm_m = 2.0;
  static constexpr double kMaxSpeed_mps = 20.0;

 private:
  using Vector9d = Eigen::Matrix<double, 9, 1>;
  using Matrix9d = Eigen::Matrix<double, 9, 9>;

  void PredictTo(double t_s);
  // A linear(ised) update with gating; returns whether it was accepted.
  template <int N>
  bool Update(const Eigen::Matrix<double, N, 1>& innovation,
              const Eigen::Matrix<double, N, 9>& jacobian,
              const Eigen::Matrix<double, N, N>& noise);
  void Start(const Eigen::Vector3d& p, double t_s);
  bool AgreesWithRay(Modality m, const GeometricAnchor& a) const;

  bool started_ = false;
  double t_s_ = 0.0;
  double last_ranging_s_ = 0.0;  // of the last accepted ranging fix (or the start)
  int rejections_ = 0;
  Motion motion_;
  Vector9d x_ = Vector9d::Zero();  // [p, v, a]; CV: a = 0 with no variance
  Matrix9d p_ = Matrix9d::Identity();
  std::optional<GeometricAnchor> ray_;                         // the latest camera ray
  std::optional<std::pair<Eigen::Vector3d, double>> pending_;  // a radar start to confirm: p, t
};

}  // namespace uavsim::pipeline
