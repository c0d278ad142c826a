#include "pipeline/node/ib_cc_config.h"

#include <string>

#include "core/json_io.h"

namespace uavsim::pipeline {

using core::Rule;

template <class V>
void Visit(V& v, IbCcConfig& c) {
  v.Enum("modality", c.modality,
         {{"camera", Modality::kCamera}, {"lidar", Modality::kLidar}, {"radar", Modality::kRadar}});
  v("latent_dim", c.latent_dim, Rule::Range(1, 4096));
  v.Check(c.latent_dim == 4 || c.latent_dim == 8 || c.latent_dim == 16 || c.latent_dim == 32 ||
              c.latent_dim == 64,
          "latent_dim",
          "expected one of 4, 8, 16, 32, 64 (paper Sec. VI), got " + std::to_string(c.latent_dim));
  v.Enum("bottleneck", c.bottleneck, {{"ib", IbBottleneck::kIb}, {"mlp", IbBottleneck::kMlp}});
  v("dropout", c.dropout, Rule{0.0, 1.0, false, true});
  v("beta", c.beta, Rule::NonNegative());
  v.Enum("mse_units", c.mse_units, IbMseUnitsNames());
  v.Object("normalization", c.normalization);
  v.Enum("stereo_branches", c.stereo_branches,
         {{"shared", StereoBranches::kShared}, {"two", StereoBranches::kTwo}});
  v("eye_pool_side", c.eye_pool_side, Rule::Range(0, 32));
  v.Check(c.eye_pool_side == 0 || 32 % c.eye_pool_side == 0, "eye_pool_side",
          "expected 0 (no pooling) or a divisor of 32, got " + std::to_string(c.eye_pool_side));
  v("roi_geometry", c.roi_geometry);
  v.Enum("point_frame", c.point_frame, PointFrameNames());
  v.Enum("point_norm", c.point_norm, PointNormNames());
}

const std::vector<std::pair<const char*, PointFrame>>& PointFrameNames() {
  static const std::vector<std::pair<const char*, PointFrame>> names = {
      {"scene", PointFrame::kScene}, {"centroid", PointFrame::kCentroid}};
  return names;
}

const std::vector<std::pair<const char*, PointNorm>>& PointNormNames() {
  static const std::vector<std::pair<const char*, PointNorm>> names = {
      {"batch", PointNorm::kBatch}, {"group", PointNorm::kGroup}, {"none", PointNorm::kNone}};
  return names;
}

const std::vector<std::pair<const char*, IbMseUnits>>& IbMseUnitsNames() {
  static const std::vector<std::pair<const char*, IbMseUnits>> names = {
      {"metres", IbMseUnits::kMetres}, {"normalised", IbMseUnits::kNormalised}};
  return names;
}

const char* IbMseUnitsName(IbMseUnits u) {
  for (const auto& [name, value] : IbMseUnitsNames())
    if (value == u) return name;
  return "?";
}

const char* PointFrameName(PointFrame f) {
  for (const auto& [name, value] : PointFrameNames())
    if (value == f) return name;
  return "?";
}

const char* PointNormName(PointNorm n) {
  for (const auto& [name, value] : PointNormNames())
    if (value == n) return name;
  return "?";
}
UAVSIM_INSTANTIATE_VISIT(IbCcConfig);

}  // namespace uavsim::pipeline
