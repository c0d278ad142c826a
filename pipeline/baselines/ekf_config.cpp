#include "pipeline/baselines/ekf_config.h"

#include "core/json_io.h"

namespace uavsim::pipeline {

using core::FormatNumber;
using core::Rule;

template <class V>
void Visit(V& v, EkfConfig& c) {
  v.Enum("motion_model", c.motion_model,
         {{"cv", EkfMotionModel::kConstantVelocity},
          {"imm", EkfMotionModel::kImm},
          {"imm_ct", EkfMotionModel::kImmCt},
          {"imm_ca_ct", EkfMotionModel::kImmCaCt}});
  // max_speed_mps, max_accel_mps2 and target_size_m are not keys: the engine
  // takes them from uavs[0] (its trajectory limits and size_m).
  v("maneuver_time_s", c.maneuver_time_s, Rule::Range(0.01, 100.0));
  v("cv_accel_fraction", c.cv_accel_fraction, Rule::Range(1e-4, 10.0));
  v("imm_cv_accel_fraction", c.imm_cv_accel_fraction, Rule::Range(1e-4, 10.0));
  v("imm_ca_jerk_fraction", c.imm_ca_jerk_fraction, Rule::Range(1e-4, 10.0));
  v("imm_cv_sojourn_s", c.imm_cv_sojourn_s, Rule::Range(0.01, 1e4));
  v("imm_ca_sojourn_s", c.imm_ca_sojourn_s, Rule::Range(0.01, 1e4));
  v("ct_accel_fraction", c.ct_accel_fraction, Rule::Range(1e-4, 10.0));
  v("ct_turn_rate_fraction", c.ct_turn_rate_fraction, Rule::Range(1e-4, 10.0));
  v("imm_ct_sojourn_s", c.imm_ct_sojourn_s, Rule::Range(0.01, 1e4));
  v("gate_probability", c.gate_probability, Rule{0.5, 1.0, false, true});
  v("max_gap_s", c.max_gap_s, Rule::Positive(1e4));
  v("ranging_timeout_s", c.ranging_timeout_s, Rule::Positive(1e4));
  v("reorder_window_s", c.reorder_window_s, Rule::NonNegative(60.0));
  v("radar_confirms_itself", c.radar_confirms_itself);
  v.Check(c.max_gap_s > c.reorder_window_s, "max_gap_s",
          "max_gap_s (" + FormatNumber(c.max_gap_s) + " s) must exceed reorder_window_s (" +
              FormatNumber(c.reorder_window_s) + " s)");
  v("lidar_floor_m", c.lidar_floor_m, Rule::NonNegative(100.0));
  v("lidar_prior_points", c.lidar_prior_points, Rule::Range(0.0, 1e6));
  v("radar_sigma_scale", c.radar_sigma_scale, Rule::Positive(1e3));
  v("radar_range_floor_m", c.radar_range_floor_m, Rule::NonNegative(100.0));
  v("radar_angle_floor_deg", c.radar_angle_floor_deg, Rule::NonNegative(90.0));
  v("radar_velocity_floor_mps", c.radar_velocity_floor_mps, Rule::NonNegative(100.0));
  v("camera_centre_sigma_px", c.camera_centre_sigma_px, Rule::Positive(1e3));
  v("camera_disparity_sigma_px", c.camera_disparity_sigma_px, Rule::Positive(1e3));
  v("camera_init_max_relative_sigma", c.camera_init_max_relative_sigma, Rule::NonNegative(10.0));
}
UAVSIM_INSTANTIATE_VISIT(EkfConfig);

}  // namespace uavsim::pipeline
