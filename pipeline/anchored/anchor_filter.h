// A Kalman filter over the geometric anchors (pipeline/anchored/anchors.h): the
// edge's filtered candidate for an anchored UAVLoc model, every fix filtered
// together where the other candidates carry one fix each to the window's
// deadline. Uses only what the nodes send with their latents: the camera's
// ray, the LiDAR centroid, the radar cluster's centroid, mean range and mean
// radial velocity.
//
// State, world ENU, SI: x = [p, v, a, omega] (Bar-Shalom, Li & Kirubarajan
// 2001, Secs. 6.2-6.3 and 11.7), with per-axis blocks of [p, v, a]:
//   constant velocity (white acceleration q_a; a stays 0):
//     F = [1 dt 0; 0 1 0; 0 0 1],  Q = q_a [dt^3/3 dt^2/2 0; dt^2/2 dt 0; 0 0 0]
//   constant acceleration (white jerk q_j):
//     F = [1 dt dt^2/2; 0 1 dt; 0 0 1],
//     Q = q_j [dt^5/20 dt^4/8 dt^3/6; dt^4/8 dt^3/3 dt^2/2; dt^3/6 dt^2/2 dt]
//   coordinated turn (horizontal velocity turning at the rate omega, about
//   the vertical; vertical velocity constant; a stays 0; Eq. 11.7.1-4;
//   CoordinatedTurn in pipeline/tracking/coordinated_turn.h):
//     p_xy += [sin(w dt)  -(1 - cos(w dt)); 1 - cos(w dt)  sin(w dt)] v_xy / w,
//     v_xy  = [cos -sin; sin cos](w dt) v_xy,  p_z += v_z dt,
//     Q the constant-velocity Q with q_a on [p, v] plus q_w dt on omega
//   interacting multiple model (Motion::kImm, the tracker's; Sec. 11.6.6;
//     pipeline/tracking/imm.h does its mixing, mode probabilities and
//     combination): a quiet coordinated turn (steady flight: an orbit, a lap
//     of a figure eight) and a manoeuvring constant velocity, each mode its
//     own Kalman filter on the common state, mixed before each prediction
//     with the switch probability 1 - exp(-dt / kModeSwitch_s) over dt, and
//     weighted after each update by its measurement's likelihood
//       log Lambda_j = -d^2 / 2 - log det(2 pi S) / 2  (d^2 = y^T S^-1 y);
//     the estimate is their moment-matched mixture; a start gives each mode
//     probability 1/2. Between ranging fixes only the rays see the target,
//     so the range along the ray runs on the model.
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
// a LiDAR fix that agrees with the latest ray (AnchorAgreesWithRay), with
// its noise, or at two radar fixes that do and agree with each other (their
// crossings of the ray), at the second with the radar's noise and its
// radial velocity: not on the ray, which may be up to
// RayGate::kGateMaxAge_s old. A LiDAR fix
// that agrees with the ray but not with the track restarts it
// (kMaxLidarRejections); after kMaxRejections ranging fixes in a row
// outside the gate, radar fixes that agree with the ray are held to confirm
// a start. kMaxCoast_s after its last ranging update (the rays alone do not
// fix the range) it coasts: any ranging fix that agrees with the ray
// (radar: confirmed) and not with the track restarts it; it predicts until
// kMaxPredict_s.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <utility>
#include <vector>

#include "pipeline/anchored/geometric_anchor.h"
#include "pipeline/node/observations.h"
#include "pipeline/tracking/coordinated_turn.h"  // CoordinatedTurn, the turn mode
#include "pipeline/tracking/imm.h"

namespace uavsim::pipeline {

class AnchorFilter {
 public:
  // Constant velocity, constant acceleration, and the IMM of a quiet
  // coordinated turn and a manoeuvring constant velocity.
  enum class Motion { kCv, kCa, kImm };
  explicit AnchorFilter(Motion motion = Motion::kCv);

  struct Estimate {
    Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
    double sigma_m = 0.0;        // sqrt of the position covariance's trace
    double ranging_age_s = 0.0;  // since the last accepted LiDAR or radar fix
    Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  };

  // Anchors of one modality, in capture order across calls (an anchor older
  // than the filter's time is applied at that time). Throws
  // std::invalid_argument for a kind that does not fit the modality.
  void Observe(Modality m, const GeometricAnchor& anchor);
  // Every anchor of a window (kNone skipped), in capture order, ties in
  // Modality order (the camera first).
  void ObserveWindow(const WindowAnchors& anchors);
  // The track predicted to t_s (not moved there), nothing before a track
  // has started or kMaxPredict_s after its last ranging update.
  std::optional<Estimate> PredictAt(double t_s) const;
  void Reset() { *this = AnchorFilter(motion_); }

  // A multi-target tracker's use (pipeline/multitarget/target_tracker.h),
  // which associates the fixes itself: no ray gate, no restarts.
  // Starts (or restarts) the track at a LiDAR or radar fix, as Observe
  // starts one (radar: at its own fix, with its radial velocity). Throws
  // std::invalid_argument for a camera's ray.
  void StartAt(Modality m, const GeometricAnchor& anchor);
  // The cost of updating the track with the anchor at its capture time:
  // the innovation's squared Mahalanobis distance d^2 (chi-square with the
  // measurement's degrees of freedom), nothing outside the gate or before
  // a start.
  std::optional<double> AssociationCost(Modality m, const GeometricAnchor& anchor) const;
  // The track predicted to the anchor's time and updated with it, gated as
  // Observe gates; returns whether it was accepted. No start, no restart.
  bool UpdateWith(Modality m, const GeometricAnchor& anchor);
  // A LiDAR or radar fix as a position and its noise: the LiDAR centroid
  // with sigma_lidar^2 I, the radar's (range along its line of sight, the
  // radar's noise above).
  struct PositionFix {
    Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
    Eigen::Matrix3d noise = Eigen::Matrix3d::Identity();
    double t_s = 0.0;
  };
  // Throws std::invalid_argument for a ray.
  static PositionFix PositionFixOf(Modality m, const GeometricAnchor& anchor);
  // log N(z - p; 0, S) of the fix against the track predicted to its time
  // (S = P_pp + R), nothing outside the 99 % gate (3 degrees of freedom) or
  // before a start.
  std::optional<double> PositionLogLikelihood(const PositionFix& fix) const;
  // The probabilistic data association update (Bar-Shalom & Tse 1975;
  // Bar-Shalom, Li & Kirubarajan 2001, Sec. 6.7 of the PDAF): fixes[j] is the
  // target's with probability beta[j], none with beta_0 = 1 - sum beta. The
  // track is predicted to the latest fix's time (each fix moved there along
  // the predicted velocity) and each mode becomes the moment-matched mixture
  // of its prediction (weight beta_0) and its update by each fix (beta_j);
  // its IMM likelihood is (1 - p_d) clutter + p_d sum_j N(nu_j; 0, S_j)
  // (clutter: the false fixes' spatial density, per m^3). Returns whether
  // anything was updated (a start and some beta_j > 0).
  bool UpdateWithMixture(const std::vector<PositionFix>& fixes, const std::vector<double>& beta,
                         double p_d, double clutter_per_m3);
  bool started() const { return started_; }
  // Capture time of the last accepted ranging fix (or the start).
  double last_ranging_s() const { return last_ranging_s_; }
  Motion motion() const { return motion_; }
  // The IMM's probability of its coordinated-turn mode (1 for kCv and kCa
  // with one mode each: 0); nothing before a start.
  std::optional<double> TurnProbability() const;

  // Noises: near the anchors' errors measured on training episodes, then
  // the best of a few settings by the track's error on them, as are the
  // IMM's q_a, q_w, switching time and its CV mode's q (NOTES.md). The
  // quiet turn's q_a is 0.005 m^2/s^3: its velocity wanders by
  // sqrt(q_a t) = 0.1 m/s in 2 s between fixes.
  static constexpr double kAccelPsd = 2.0;              // CV: q, m^2/s^3
  static constexpr double kJerkPsd = 1.0;               // CA: q, m^2/s^5
  static constexpr double kTurnAccelPsd = 0.005;        // CT: q_a, m^2/s^3
  static constexpr double kTurnRatePsd = 1e-4;          // CT: q_w, rad^2/s^3
  static constexpr double kStartTurnSigma_rps = 0.3;    // IMM: omega at a start
  static constexpr double kModeSwitch_s = 5.0;          // IMM: mean time in a mode
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
  // Ranging fixes in a row outside the gate after which radar fixes that
  // agree with the ray are held to confirm a start; LiDAR fixes in a row
  // outside the gate after which one that agrees with the ray restarts the
  // track (a LiDAR cluster gated by the ray is the drone in clear air).
  static constexpr int kMaxRejections = 3;
  static constexpr int kMaxLidarRejections = 1;
  // A second radar fix confirms a first within this distance (plus the
  // distance kMaxSpeed_mps covers in between).
  static constexpr double kConfirm_m = 2.0;
  static constexpr double kMaxSpeed_mps = 20.0;

 private:
  using Vector10d = Eigen::Matrix<double, 10, 1>;
  using Matrix10d = Eigen::Matrix<double, 10, 10>;
  enum class Model { kCv, kCa, kCt };
  using Imm10 = Imm<10>;  // x = [p, v, a, omega]

  void PredictTo(double t_s);
  // A camera ray: held, and an update normal to it when a track runs;
  // whether the update was accepted.
  bool ObserveRay(const GeometricAnchor& a);
  // A LiDAR or radar fix as an update of the running track (predicted to
  // its time); returns whether the gate accepted it.
  bool UpdateRanging(Modality m, const GeometricAnchor& a);
  // A (re)start at a ranging fix that agrees with the ray, when no live,
  // trusted track runs (or a radar fix to confirm).
  void MaybeRestart(Modality m, const GeometricAnchor& a, bool live);
  // Mixes the modes' estimates into the one the filter reports.
  void Combine();
  // A linear(ised) update with gating on the mixture: `measure(x)` gives
  // the innovation and its Jacobian at x. Returns whether it was accepted.
  template <int N, class Measure>
  bool Update(const Measure& measure, const Eigen::Matrix<double, N, N>& noise);
  // At a LiDAR fix p at t_s, or (radar) at a radar's fix, whose crossing of
  // the ray is p.
  void Start(const Eigen::Vector3d& p, double t_s, const GeometricAnchor* radar);
  bool AgreesWithRay(Modality m, const GeometricAnchor& a) const;

  bool started_ = false;
  double t_s_ = 0.0;
  double last_ranging_s_ = 0.0;  // of the last accepted ranging fix (or the start)
  int rejections_ = 0;
  int lidar_rejections_ = 0;  // in a row
  Motion motion_;
  std::vector<Model> models_;        // each mode's motion model, in imm_'s order
  Imm10 imm_;                        // the bank of Kalman filters: one mode each
  Vector10d x_ = Vector10d::Zero();  // the mixture
  Matrix10d p_ = Matrix10d::Identity();
  std::optional<GeometricAnchor> ray_;                         // the latest camera ray
  std::optional<std::pair<Eigen::Vector3d, double>> pending_;  // a radar start to confirm: p, t
  // Set (AssociationCost, on a copy): Update computes the gated d^2 here
  // and changes nothing.
  std::optional<double>* probe_ = nullptr;
};

}  // namespace uavsim::pipeline
