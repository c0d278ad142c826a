#include "pipeline/pipeline_config.h"

#include "sim/core/json_io.h"

namespace uavsim::pipeline {

using core::Rule;

const std::vector<std::string>& KnownMethods() {
  static const std::vector<std::string> names{"uavloc",      "uavloc_anchored", "anchor_track",
                                              "ekf",         "uavloc_camera",   "uavloc_lidar",
                                              "uavloc_radar"};
  return names;
}

template <class V>
void Visit(V& v, PipelineConfig& c) {
  v("model", c.model);
  v.Check(!c.model.empty(), "model", "expected \"default\" or the path of a trained model");
  v("window_s", c.window_s, Rule{0.0, 10.0, true, false});
  v("latent_dim", c.latent_dim, Rule::Range(1, 4096));
  v.Check(c.latent_dim == 4 || c.latent_dim == 8 || c.latent_dim == 16 || c.latent_dim == 32 ||
              c.latent_dim == 64,
          "latent_dim",
          "expected one of 4, 8, 16, 32, 64 (paper Sec. VI), got " + std::to_string(c.latent_dim));
  v("late_allowance_s", c.late_allowance_s, Rule::NonNegative(10.0));
  v("methods", c.methods, KnownMethods());
  v("uavloc_wait_for_track", c.uavloc_wait_for_track);
  v.Object("preprocess", c.preprocess);
  v.Object("ekf", c.ekf);
}
UAVSIM_INSTANTIATE_VISIT(PipelineConfig);

}  // namespace uavsim::pipeline
