// The classical baseline a user would pick instead of UAVLoc (issue 6 item
// 5): an extended Kalman filter (by default an IMM of a constant-velocity, a
// constant-acceleration and a coordinated-turn EKF, "imm_ca_ct") that fuses the same pre-processed
// observations as the learned pipeline (pipeline/node/observations.h)
// asynchronously, with noises set from the sensors' configurations and the
// target's limits. Its estimates are the `ekf` rows of estimates.csv.
//
// State, world frame ENU, SI units: x = [p (m), v (m/s), a (m/s^2),
// omega (rad/s)], 10-D, the same layout for every motion model: CV and the
// coordinated turn carry a = 0; omega, the horizontal velocity's turn rate
// about the vertical (counter-clockwise positive), is the coordinated turn's
// own. A mode that does not model a component carries it unchanged (CV, CA:
// omega) or zeroes it (CV, CT: a); mixed into a mode that models it, it
// borrows that mode's mean and covariance for it, uncorrelated with the rest
// (below). Without a coordinated-turn mode ("cv", "imm") omega stays 0 with
// variance 0: the filter is the 9-D [p, v, a] one.
//
// Motion models, per axis, with white-noise spectral densities (Bar-Shalom,
// Li & Kirubarajan, "Estimation with Applications to Tracking and
// Navigation", 2001, Secs. 6.2-6.3):
//   CV (white acceleration, q_a in m^2/s^3): p' = v, v' = w, a = 0,
//     F = [1 dt; 0 1],  Q = q_a [dt^3/3 dt^2/2; dt^2/2 dt]
//   CA (white jerk, q_j in m^2/s^5): p' = v, v' = a, a' = w,
//     F = [1 dt dt^2/2; 0 1 dt; 0 0 1],
//     Q = q_j [dt^5/20 dt^4/8 dt^3/6; dt^4/8 dt^3/3 dt^2/2; dt^3/6 dt^2/2 dt]
//   With a_max = max_accel_mps2 and T = maneuver_time_s: a white process of
//   density q averaged over T has variance q / T, so a mean acceleration of
//   sigma_a over a manoeuvre of T needs q_a = sigma_a^2 T, and an
//   acceleration that drifts by sigma_da within T needs q_j = sigma_da^2 / T:
//     "cv":  q_a = (cv_accel_fraction a_max)^2 T            (0.3: 2.25 m^2/s^3)
//     "imm": CV mode, for manoeuvres, q_a = (imm_cv_accel_fraction a_max)^2 T
//            (0.3: a stop-and-go's acceleration steps), CA mode, for smooth
//            turns, q_j = (imm_ca_jerk_fraction a_max)^2 / T (0.1: an orbit's
//            centripetal acceleration, 6 m/s on 25 m, turns at 0.35 m/s^3).
//   CT (coordinated turn, Bar-Shalom et al. Sec. 11.7, Eq. 11.7.1-4;
//     CoordinatedTurn in pipeline/tracking/coordinated_turn.h):
//     p_xy += [sin(w dt)  -(1 - cos(w dt)); 1 - cos(w dt)  sin(w dt)] v_xy / w,
//     v_xy = [cos -sin; sin cos](w dt) v_xy, p_z += v_z dt, a = 0, w kept;
//     linearised (F its Jacobian at the mode's mean); Q the CV Q with
//     q_a = (ct_accel_fraction a_max)^2 T on [p, v] of every axis, plus
//     q_w dt on omega with q_w = (ct_turn_rate_fraction a_max / v_max)^2 / T
//     (a_max / v_max the rate of a full-acceleration turn at full speed:
//     0.5 rad/s by default; the default orbit turns at 0.24 rad/s).
//     "imm_ct":    CV (imm_cv_accel_fraction) + CT, the anchor filter's pair
//                  (pipeline/anchored/anchor_filter.h);
//     "imm_ca_ct": CV + CA + CT, the default.
//   The defaults come from the process-noise sweeps "[tuning]" in
//   tests/pipeline/baselines/ekf_test.cpp, on simulated training episodes
//   (8 x 60 s of each trajectory type, seeds 100-107), never on a reported
//   scenario; what they measured is in NOTES.md (session 5, and session 16's
//   "moved from headers").
//   IMM (Blom & Bar-Shalom 1988; pipeline/tracking/imm.h does its mixing,
//   mode probabilities and combination): mode switches are a continuous-time
//   Markov chain leaving mode i at rate 1 / sojourn_i (for any other mode alike), so
//   over any dt Pi(dt) = exp(Lambda dt) exactly (asynchronous updates need
//   no fixed step); mixing, mode-matched EKF updates, mode probabilities
//   from the innovation likelihoods
//     log Lambda_j = -(y^T S^-1 y + log det S + dim log 2 pi) / 2;
//   the output is the moment-matched mixture. Mixed into the CA mode, a
//   mode without acceleration (CV, CT) borrows the CA mode's acceleration,
//   and mixed into the CT mode, a mode without turn rate (CV, CA) borrows
//   the CT mode's omega (Granstrom, Willett & Bar-Shalom 2015,
//   unequal-dimension mixing): mean and variance the receiving mode's, no
//   cross-covariance. A track starts in the chain's stationary distribution,
//   mu_i = sojourn_i / sum_l sojourn_l, with omega = 0 of variance
//   (a_max / v_max)^2 / 3 (uniform over +-a_max / v_max) when a mode models it.
//
// Measurements, each applied at its own timestamp tau (predict to tau, then
// update; Joseph-form covariance update):
//   LiDAR (PointObservation, 4 channels): the centroid c of the N dynamic
//     points, a 3-D position. With u the unit line of sight from the LiDAR,
//     R = |c - s|, E the covariance of a point spread uniformly over the
//     target's box (level, yaw unknown: both horizontal axes get
//     (sx^2 + sy^2) / 24, the vertical sz^2 / 12), sigma_r = range_noise_m
//     and f = beam_divergence R the beam's footprint at that range:
//       per-point prior   S0 = E + sigma_r^2 u u^T + f^2/16 (I - u u^T)
//       per-point         S1 = (nu S0 + (N - 1) S) / (nu + N - 1)   (S: sample covariance)
//       centroid          Cov = S1 / N + lidar_floor_m^2 I
//     nu = lidar_prior_points. A point lies on the target whatever the scan
//     spacing (the spacing sets N, which is counted): the model has no
//     scan-spacing term.
//   Radar (PointObservation, 5 channels; t_s the frame's start, so the
//     detections are applied at t_s + N_chirps T_c / 2, the chirps' middle):
//     each detection d = R_WR^T (p - s) in the radar frame
//     (sensors/fmcw_radar.h conventions) gives
//       z = [range, azimuth, elevation, radial velocity (+ = receding)],
//       h(p, v) = [|d|, atan2(d_y, d_x), asin(d_z / |d|), (p - s).v / |p - s|]
//     with resolutions from FmcwRadarConfig (RadarResolutionOf):
//       dR = c / (2 B_s), B_s the bandwidth swept while the ADC samples;
//       dv = lambda / (2 N_chirps T_c); du = 1 / (N spacing_wavelengths) in
//       direction cosines (2/N rad at lambda/2 spacing)
//     and the estimation accuracy rule sigma = k res / sqrt(2 SNR), k =
//     radar_sigma_scale, SNR = M snr the array's: snr_db is a cell's
//     per-antenna SNR (sensors/radar_processor.h) and M = nx ny antennas
//     add coherently:
//       sigma_R^2 = (k dR)^2 / (2 SNR),   sigma_v^2 = (k dv)^2 / (2 SNR),
//       sigma_uy^2, sigma_uz^2 = (k du)^2 / (2 SNR), mapped to (azimuth,
//       elevation) through u_y = cos el sin az, u_z = sin el,
//     plus a per-frame error common to all of a frame's detections,
//     diag(radar_range_floor_m, radar_angle_floor_deg x2, radar_velocity_floor_mps)^2.
//     A frame's gated detections (its 16 strongest
//     at most) are one stacked update whose noise has the common part in
//     every cross block. Azimuth innovations wrap to (-pi, pi]; velocity
//     innovations to the unambiguous interval +-lambda / (4 T_c).
//   Camera (CameraObservation, detected): the two unit rays from the eyes
//     through the ROI centres. z = both rays' components on an orthonormal
//     pair (e1, e2) normal to the predicted line of sight, h(p) the same
//     for the unit vectors (p - eye) / |p - eye|. Stereo triangulation of
//     the rays (midpoint of their shortest segment) is what these four
//     numbers say about p; the filter uses the rays themselves because at
//     this scenario's ranges the disparity is below a pixel (a 0.12 m
//     baseline at 50 m) and a triangulated point is far from Gaussian, while
//     the rays are; the update is the same to first order where
//     triangulation is well conditioned. Noise: a pixel error sigma maps to
//     angle through the Mei model r(theta) = f sin(theta) / (cos(theta) + xi)
//     at the ray's angle theta from the optical axis (f = (fx + fy) / 2):
//       radially sigma (cos th + xi)^2 / (f (1 + xi cos th)),
//       tangentially sigma (cos th + xi) / f   (both (1 + xi) sigma / f on axis).
//     The right eye's ROI is the left's moved by the stereo match
//     (camera pre-processing), so the ROI-centre error (camera_centre_sigma_px)
//     is common to both eyes and only the match error
//     (camera_disparity_sigma_px, both image axes) is the right eye's own:
//       Cov = [C, C; C, C + D].
//     Depth error of the triangulation: sigma_Z ~ Z^2 sigma_angle sqrt(2) / b.
//
// Gating: each component (a LiDAR fix, a camera pair, one radar detection)
// is tested against the combined prediction: accepted when
// y^T S^-1 y <= chi2_inv(gate_probability, dim y). A measurement wholly
// outside the gate leaves the track untouched.
//
// Track management. "Ranging" measurements are those that fix p in 3-D: a
// LiDAR fix, a radar frame, a position fix, and a camera pair whose
// triangulation has a relative depth error of at most
// camera_init_max_relative_sigma. A ranging measurement starts a tentative
// track (a radar frame from its strongest detection, velocity known along
// the line of sight only; unknown velocity has variance max_speed^2/3 per
// axis, acceleration max_accel^2/3); a second ranging measurement inside
// its gate confirms it (with radar_confirms_itself false, for a track a
// radar started, one of another node when there is one: a radar's clutter,
// rain echoes or a multipath ghost, stands at the same range and angle frame
// after frame and would confirm itself), one outside restarts it, three
// rejections in a row
// drop it. Estimates come from confirmed tracks only. A confirmed track
//   - is lost after max_gap_s without an accepted update, and then
//     re-acquired like a new one (its predicted covariance would open the
//     gate to any false alarm); its estimate is extrapolated at most
//     max_gap_s past the last update and held there;
//   - once no ranging measurement has been accepted for ranging_timeout_s,
//     lets a rejected ranging measurement start a candidate; a second one
//     (of another node for a radar's candidate, as above) rejected by the
//     track but accepted by the candidate replaces the track (camera rays cannot tell a wrong
//     range; a lone false alarm cannot take a good track away).
//
// Out-of-order measurements: observations are buffered for
// reorder_window_s behind the newest time seen (an observation's timestamp
// or a query), kept sorted by (timestamp, node, arrival), and folded into
// the committed state once strictly older than that; a query runs a copy of
// the committed state through the buffer. Any arrival order within the
// window gives bit-identical results to in-order arrival; an observation
// older than the window is dropped and counted in `too_late`.
//
// Inputs must be the pre-processed observations: a raw-variant camera
// observation (ablations) reports the optical axes as bearings, which the
// gate will reject.
//
// Thread safety: none (one Ekf per run). Deterministic: no randomness.
// Errors: std::invalid_argument for an unknown or duplicate node id, an
// observation of the wrong type or channel count for its node.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/baselines/ekf_config.h"
#include "pipeline/node/observations.h"
#include "pipeline/tracking/imm.h"
#include "sensors/fisheye_stereo_config.h"
#include "sensors/fmcw_radar_config.h"
#include "sensors/lidar_config.h"

namespace uavsim::pipeline {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

// A position measurement with its covariance: the LiDAR centroid, or any
// other localizer's output fed in as a measurement.
struct PositionFix {
  double t_s = 0.0;
  Eigen::Vector3d position_w = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance_m2 = Eigen::Matrix3d::Identity();
};

// The filter's estimate at a time: moment-matched over the IMM's modes.
struct EkfEstimate {
  double t_s = 0.0;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  Matrix6d covariance = Matrix6d::Identity();  // of [p, v]: m^2, m^2/s, m^2/s^2
  double time_since_update_s = 0.0;
  // "cv": {1}; "imm": {CV, CA}; "imm_ct": {CV, CT}; "imm_ca_ct": {CV, CA, CT}.
  std::vector<double> mode_probabilities;
};

// Per-node counters, for the run's diagnostics. Counted once per
// observation, when it is committed (not when a query re-runs the buffer).
struct EkfNodeStats {
  std::size_t observations = 0;  // received, including undetected and too late
  std::size_t too_late = 0;      // older than the reorder window: dropped
  std::size_t accepted = 0;      // components inside the gate (a radar frame has one per detection)
  std::size_t rejected = 0;      // components outside the gate
  std::size_t initiations = 0;   // tracks started (or taken over from a candidate) here
  double nis_sum = 0.0;          // of accepted components, against the combined prediction
  std::size_t nis_dof = 0;
  // Near 1 (slightly below: the gate truncates the tail) when the noise
  // model is honest; well above 1 means the stated noise is too small.
  double MeanNisPerDof() const { return nis_dof ? nis_sum / static_cast<double>(nis_dof) : 0.0; }
};

class Ekf {
 public:
  explicit Ekf(const EkfConfig& config);

  // Registers a sensing node; its configuration sets its noise model.
  void AddCamera(const std::string& node_id, const sensors::FisheyeStereoConfig& config);
  void AddLidar(const std::string& node_id, const sensors::LidarConfig& config);
  void AddRadar(const std::string& node_id, const sensors::FmcwRadarConfig& config);
  // A source of PositionFix measurements (tests, other localizers).
  void AddPositionSource(const std::string& node_id);

  // Hands over one observation, in any order within reorder_window_s.
  void Observe(const std::string& node_id, const CameraObservation& observation);
  void Observe(const std::string& node_id, const PointObservation& observation);
  void Observe(const std::string& node_id, const PositionFix& fix);

  // The position predicted at t_s (a window deadline) from every
  // observation with a timestamp up to t_s; nullopt while no track is
  // confirmed (before the first, or after a lost one was dropped). Moves the
  // newest time seen to t_s. A t_s older than the committed state
  // extrapolates its mean backwards (the committed state already holds
  // later measurements).
  std::optional<Eigen::Vector3d> EstimateAt(double t_s);
  std::optional<EkfEstimate> StateAt(double t_s);

  const EkfNodeStats& stats(const std::string& node_id) const;  // throws std::invalid_argument
  const EkfConfig& config() const { return config_; }

  // Process-noise densities the config gives (formulas above).
  double CvAccelPsd() const;     // m^2/s^3, the "cv" model or the IMM's CV mode
  double CaJerkPsd() const;      // m^2/s^5, the IMM's CA mode
  double CtAccelPsd() const;     // m^2/s^3, the CT mode's q_a
  double CtTurnRatePsd() const;  // rad^2/s^3, the CT mode's q_w

 private:
  using Vector10d = Eigen::Matrix<double, 10, 1>;
  using Matrix10d = Eigen::Matrix<double, 10, 10>;
  // One piece of a measurement, linearised at a state: innovation z - h(x),
  // Jacobian dh/dx (dim x 10) and noise covariance (dim x dim).
  struct Linearization {
    Eigen::VectorXd innovation;
    Eigen::MatrixXd jacobian;
    Eigen::MatrixXd noise;
  };
  struct TrackStart {
    Eigen::Vector3d position_m;
    Eigen::Matrix3d position_cov;
    Eigen::Vector3d velocity_mps;
    Eigen::Matrix3d velocity_cov;
  };
  // An observation made ready for the filter: its components (gated one by
  // one, updated together), the noise shared by every pair of components
  // (radar frames), and how it would start a track.
  struct Measurement {
    double t_s = 0.0;
    int node = 0;
    std::uint64_t arrival = 0;
    std::vector<std::function<Linearization(const Vector10d&)>> components;
    Eigen::MatrixXd common_noise;  // empty: independent components
    std::optional<TrackStart> start;
  };
  using Imm10 = Imm<10>;
  struct Track {
    bool initialized = false;
    bool confirmed = false;  // a ranging measurement has been accepted since the start
    int start_node = -1;     // the node whose measurement started it
    int rejections = 0;      // in a row, while not confirmed
    double t_s = 0.0;
    double t_last_update_s = 0.0;  // last accepted update
    double t_last_anchor_s = 0.0;  // last accepted ranging measurement
    Imm10 imm;                     // the modes' estimates and probabilities, in modes_'s order
  };
  enum class NodeKind { kCamera, kLidar, kRadar, kPosition };
  struct Node {
    std::string id;
    NodeKind kind = NodeKind::kPosition;
    sensors::FisheyeStereoConfig camera;
    sensors::LidarConfig lidar;
    sensors::FmcwRadarConfig radar;
    EkfNodeStats stats;
    std::uint64_t arrivals = 0;
  };

  int AddNode(const std::string& node_id, NodeKind kind);
  Node& NodeOf(const std::string& node_id, NodeKind kind);
  static Linearization LinearPosition(const Eigen::Vector3d& z, const Eigen::Matrix3d& R,
                                      const Vector10d& x);
  Measurement PrepareCamera(const Node& node, const CameraObservation& o) const;
  Measurement PrepareLidar(const Node& node, const PointObservation& o) const;
  Measurement PrepareRadar(const Node& node, const PointObservation& o) const;
  void Enqueue(Node& node, Measurement m);
  void AdvanceHorizon(double t_s);
  // The track, and a candidate started by a ranging measurement the track
  // rejected (header comment, "Track management").
  struct Tracks {
    Track main;
    Track candidate;
  };
  void Apply(Tracks& tracks, const Measurement& m, EkfNodeStats* stats) const;
  // Predict, gate, update; the number of components accepted.
  int Update(Track& track, const Measurement& m, EkfNodeStats* stats) const;
  void Start(Track& track, const TrackStart& start, double t_s) const;
  void Predict(Track& track, double t_s) const;
  EkfEstimate Combine(const Track& track, double t_s) const;
  double GateThreshold(int dof) const;

  EkfConfig config_;
  std::vector<Node> nodes_;
  std::map<std::string, int> node_index_;
  Tracks committed_;
  std::vector<Measurement> buffer_;  // sorted by (t_s, node, arrival)
  double horizon_s_ = -1e300;        // newest time seen minus reorder_window_s
  enum class ModeKind { kCv, kCa, kCt };
  struct ModeModel {
    ModeKind kind = ModeKind::kCv;
    double psd = 0.0;        // CV, CT: q_a (m^2/s^3); CA: q_j (m^2/s^5)
    double turn_psd = 0.0;   // CT: q_w (rad^2/s^3)
    double sojourn_s = 1.0;  // mean time before switching (IMM)
  };
  bool HasMode(ModeKind kind) const;
  std::vector<ModeModel> modes_;
  std::vector<double> gate_by_dof_;
};

// --- Sensor models, for the filter and for tests. ---

// Theoretical resolutions of an FMCW radar (sensors/fmcw_radar.h).
struct RadarResolution {
  double range_m = 0.0;             // c / (2 B_s), B_s = bandwidth * ADC window / chirp duration
  double velocity_mps = 0.0;        // lambda / (2 N_chirps (T_chirp + T_idle))
  double max_velocity_mps = 0.0;    // unambiguous: lambda / (4 (T_chirp + T_idle))
  double direction_cosine_y = 0.0;  // 1 / (nx spacing_x_wavelengths)
  double direction_cosine_z = 0.0;  // 1 / (ny spacing_y_wavelengths)
};
RadarResolution RadarResolutionOf(const sensors::FmcwRadarConfig& config);

// The LiDAR centroid fix of a cloud (channels 4: x y z intensity), with the
// covariance of the header comment; nullopt for an empty cloud.
std::optional<PositionFix> LidarCentroidFix(const PointObservation& observation,
                                            const sensors::LidarConfig& lidar,
                                            const EkfConfig& config);

// Radar measurement h(p, v) = [range m, azimuth rad, elevation rad, radial
// velocity m/s] of a target at p with velocity v (world), for a radar at
// radar_w whose frame R has rotation R_WR; and its Jacobian d h / d [p, v].
Eigen::Vector4d RadarMeasurement(const Eigen::Vector3d& p, const Eigen::Vector3d& v,
                                 const Eigen::Vector3d& radar_w, const Eigen::Matrix3d& R_WR);
Eigen::Matrix<double, 4, 6> RadarJacobian(const Eigen::Vector3d& p, const Eigen::Vector3d& v,
                                          const Eigen::Vector3d& radar_w,
                                          const Eigen::Matrix3d& R_WR);

// Midpoint of the shortest segment between two rays o + t d (d unit),
// t the distances along each ray; nullopt for parallel rays or a point
// behind either eye.
struct Triangulation {
  Eigen::Vector3d point_w = Eigen::Vector3d::Zero();
  double range_left_m = 0.0;
  double range_right_m = 0.0;
  double gap_m = 0.0;  // length of the shortest segment
};
std::optional<Triangulation> TriangulateMidpoint(const Eigen::Vector3d& eye_left_w,
                                                 const Eigen::Vector3d& ray_left_w,
                                                 const Eigen::Vector3d& eye_right_w,
                                                 const Eigen::Vector3d& ray_right_w);

// Radians per pixel of the Mei model at angle theta from the optical axis:
// {radial, tangential} (header comment).
Eigen::Vector2d FisheyeRadPerPixel(double theta_rad, double focal_px, double xi);

// Inverse of the chi-square CDF with `dof` degrees of freedom, p in (0, 1).
double ChiSquareQuantile(double p, int dof);

}  // namespace uavsim::pipeline
