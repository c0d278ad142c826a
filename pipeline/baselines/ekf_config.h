// Parameters of the EKF baseline (pipeline/baselines/ekf.h has the models and the
// formulas each key enters), under the scenario's /pipeline/ekf. The
// measurement noises come from the sensors' own configurations; the keys
// here are what a sensor configuration cannot say: the target's limits and
// size, the process noise, gating and track management, and floors for
// errors no resolution formula covers (calibration, the target's extent).
#pragma once

#include <Eigen/Core>

namespace uavsim::pipeline {

enum class EkfMotionModel {
  kConstantVelocity,  // "cv": one constant-velocity model, white-noise
                      // acceleration
  kImm,               // "imm": interacting multiple models, constant velocity + constant
                      // acceleration
  kImmCt,             // "imm_ct": constant velocity + coordinated turn (the anchor filter's
                      // pair)
  kImmCaCt,           // "imm_ca_ct": constant velocity + constant acceleration +
                      // coordinated turn
};

struct EkfConfig {
  EkfMotionModel motion_model = EkfMotionModel::kImmCaCt;

  // The target: its trajectory's limits and its size. Not scenario keys: the
  // engine copies uavs[0].trajectory.max_speed_mps, max_accel_mps2 and
  // uavs[0].size_m here.
  double max_speed_mps = 10.0;
  double max_accel_mps2 = 5.0;
  Eigen::Vector3d target_size_m{0.5, 0.5, 0.2};

  // Process noise, as fractions of max_accel_mps2 over a manoeuvre of
  // maneuver_time_s (ekf.h, "Motion models"). "cv": white acceleration of
  // spectral density (cv_accel_fraction a_max)^2 maneuver_time_s. "imm": a CV
  // mode for manoeuvres (imm_cv_accel_fraction), and a CA mode for smooth
  // turns whose white jerk lets the acceleration drift by
  // imm_ca_jerk_fraction a_max within maneuver_time_s; mean times spent in
  // each mode before switching. Tuned on simulated trajectories of all four
  // types (tests/pipeline/baselines/ekf_test.cpp, "[tuning]").
  double maneuver_time_s = 1.0;
  double cv_accel_fraction = 0.3;
  double imm_cv_accel_fraction = 0.3;
  double imm_ca_jerk_fraction = 0.1;
  double imm_cv_sojourn_s = 2.0;
  double imm_ca_sojourn_s = 3.0;
  // The coordinated-turn mode ("imm_ct", "imm_ca_ct"; ekf.h, "Motion
  // models"): white acceleration on [p, v] per axis of spectral density
  // (ct_accel_fraction a_max)^2 maneuver_time_s (m^2/s^3), and a turn rate
  // omega (rad/s) that drifts by ct_turn_rate_fraction a_max / v_max (the
  // rate of a full-acceleration turn at full speed) within maneuver_time_s:
  // q_w = (ct_turn_rate_fraction a_max / v_max)^2 / maneuver_time_s
  // (rad^2/s^3); mean time (s) spent in the mode before switching. The CV
  // mode of every IMM uses imm_cv_accel_fraction and imm_cv_sojourn_s.
  // The defaults: "[tuning]", "coordinated-turn noise sweep" (ekf.h).
  double ct_accel_fraction = 0.01;
  double ct_turn_rate_fraction = 0.02;
  double imm_ct_sojourn_s = 3.0;

  // Gating and track management.
  double gate_probability = 0.99;  // chi-square gate per measurement component
  double max_gap_s = 2.0;          // no update for this long: the track is lost (re-acquired
                                   // like a new one) and its estimate held since
  double ranging_timeout_s = 1.0;  // no ranging measurement accepted for this long: two
                                   // consistent rejected ones replace the track
  double reorder_window_s = 0.2;   // out-of-order tolerance: measurements this much older
                                   // than the newest time seen are still applied in order
  // Whether a radar's next frame may confirm the track its own frame started.
  // false: another node must (a radar's rain clutter stands still frame after
  // frame and confirms itself; but in fog, where LiDAR and camera fail, the
  // radar alone then never starts a track). Measured in NOTES.md.
  bool radar_confirms_itself = true;

  // LiDAR centroid: floor on its standard deviation per axis (the visible
  // surface's offset from the target's centre), and the pseudo-count of the
  // prior per-point covariance against the cluster's sample covariance.
  double lidar_floor_m = 0.04;
  double lidar_prior_points = 10.0;

  // Radar: scale on the resolution-over-sqrt(2 SNR) terms, and per-frame
  // floors common to all detections of a frame (calibration, multipath).
  double radar_sigma_scale = 1.0;
  double radar_range_floor_m = 0.05;
  double radar_angle_floor_deg = 0.5;
  double radar_velocity_floor_mps = 0.05;

  // Camera: ROI-centre error in the left eye (fisheye pixels, carried into
  // the right eye by the stereo match), the stereo match's own error, and
  // the largest relative depth error of a triangulation that may start a track.
  double camera_centre_sigma_px = 0.25;
  double camera_disparity_sigma_px = 0.2;
  double camera_init_max_relative_sigma = 0.1;
};

template <class V>
void Visit(V& v, EkfConfig& c);

}  // namespace uavsim::pipeline
