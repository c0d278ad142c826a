#include "pipeline/node/ib_normalization.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/json_io.h"

namespace uavsim::pipeline {

using core::Rule;

template <class V>
void Visit(V& v, IbNormalization& c) {
  v("centre_m", c.centre_m);
  v("scale_m", c.scale_m, Rule::Positive());
  v("image_width_px", c.image_width_px, Rule::Positive());
  v("image_height_px", c.image_height_px, Rule::Positive());
  v("intensity_scale", c.intensity_scale, Rule::Positive());
  v("velocity_scale_mps", c.velocity_scale_mps, Rule::Positive());
  v("snr_offset_db", c.snr_offset_db);
  v("snr_scale_db", c.snr_scale_db, Rule::Positive());
}
UAVSIM_INSTANTIATE_VISIT(IbNormalization);

IbNormalization FitPositionNormalization(const std::vector<Eigen::Vector3d>& positions_w,
                                         const IbNormalization& base) {
  if (positions_w.empty())
    throw std::invalid_argument("FitPositionNormalization: no positions to fit");
  IbNormalization n = base;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto& p : positions_w) sum += p;
  n.centre_m = sum / static_cast<double>(positions_w.size());
  Eigen::Vector3d sq = Eigen::Vector3d::Zero();
  for (const auto& p : positions_w) sq += (p - n.centre_m).cwiseAbs2();
  const double std_max = std::sqrt(sq.maxCoeff() / static_cast<double>(positions_w.size()));
  // A hovering target has no spread; 1 m keeps the scale meaningful.
  n.scale_m = std::max(std_max, 1.0);
  return n;
}

Eigen::Vector3d NormalizePosition(const Eigen::Vector3d& p_w, const IbNormalization& n) {
  return (p_w - n.centre_m) / n.scale_m;
}

Eigen::Vector3d DenormalizePosition(const Eigen::Vector3d& p_n, const IbNormalization& n) {
  return p_n * n.scale_m + n.centre_m;
}

std::vector<float> CameraGeometryFeatures(const CameraObservation& obs, const IbNormalization& n) {
  const double half_w = 0.5 * n.image_width_px;
  const double half_h = 0.5 * n.image_height_px;
  const Eigen::Vector3d eye_l = NormalizePosition(obs.eye_left_w, n);
  const Eigen::Vector3d eye_r = NormalizePosition(obs.eye_right_w, n);
  std::vector<float> f;
  f.reserve(kCameraGeometryFeatures);
  f.push_back(static_cast<float>((obs.centre_left_px.x() - half_w) / half_w));
  f.push_back(static_cast<float>((obs.centre_left_px.y() - half_h) / half_h));
  f.push_back(static_cast<float>((obs.centre_right_px.x() - half_w) / half_w));
  f.push_back(static_cast<float>((obs.centre_right_px.y() - half_h) / half_h));
  f.push_back(static_cast<float>(obs.side_left_px / n.image_width_px));
  f.push_back(static_cast<float>(obs.side_right_px / n.image_width_px));
  for (int i = 0; i < 3; ++i) f.push_back(static_cast<float>(obs.bearing_left_w[i]));
  for (int i = 0; i < 3; ++i) f.push_back(static_cast<float>(obs.bearing_right_w[i]));
  for (int i = 0; i < 3; ++i) f.push_back(static_cast<float>(eye_l[i]));
  for (int i = 0; i < 3; ++i) f.push_back(static_cast<float>(eye_r[i]));
  return f;
}

int PointChannels(Modality m) {
  switch (m) {
    case Modality::kLidar:
      return 4;
    case Modality::kRadar:
      return 5;
    case Modality::kCamera:
      break;
  }
  throw std::invalid_argument("PointChannels: the camera modality has no point channels");
}

void NormalizePoints(const PointObservation& obs, Modality m, const IbNormalization& n,
                     float* out) {
  const int channels = PointChannels(m);
  if (obs.channels != channels)
    throw std::invalid_argument("NormalizePoints: expected " + std::to_string(channels) +
                                " channels per point, got " + std::to_string(obs.channels));
  if (obs.values.size() % static_cast<std::size_t>(channels) != 0)
    throw std::invalid_argument("NormalizePoints: " + std::to_string(obs.values.size()) +
                                " values is not a whole number of " + std::to_string(channels) +
                                "-channel points");
  const std::size_t count = obs.count();
  if (count > static_cast<std::size_t>(PointObservation::kMaxPoints))
    throw std::invalid_argument("NormalizePoints: " + std::to_string(count) + " points, at most " +
                                std::to_string(PointObservation::kMaxPoints) + " allowed");
  for (std::size_t k = 0; k < obs.values.size(); ++k)
    if (!std::isfinite(obs.values[k]))
      throw std::invalid_argument("NormalizePoints: point " +
                                  std::to_string(k / static_cast<std::size_t>(channels)) +
                                  " has a non-finite value");
  for (std::size_t i = 0; i < count; ++i) {
    const float* p = &obs.values[i * static_cast<std::size_t>(channels)];
    for (int a = 0; a < 3; ++a)
      out[static_cast<std::size_t>(a) * count + i] =
          static_cast<float>((p[a] - n.centre_m[a]) / n.scale_m);
    if (m == Modality::kLidar) {
      out[3 * count + i] = static_cast<float>(p[3] / n.intensity_scale);
    } else {
      out[3 * count + i] = static_cast<float>(p[3] / n.velocity_scale_mps);
      out[4 * count + i] = static_cast<float>((p[4] - n.snr_offset_db) / n.snr_scale_db);
    }
  }
}

}  // namespace uavsim::pipeline
