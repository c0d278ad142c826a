#include "core/pose.h"

#include <cmath>

#include "core/json_io.h"
#include "core/physical_constants.h"

namespace uavsim::core {

Eigen::Isometry3d PoseConfig::ToIsometry() const {
  const Eigen::Vector3d rpy = rpy_deg * kDegToRad;
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  X.translation() = position_m;
  return X;
}

template <class V>
void Visit(V& v, PoseConfig& c) {
  v("position_m", c.position_m, Rule::Range(-1e6, 1e6));
  v("rpy_deg", c.rpy_deg, Rule::Range(-360, 360));
}
UAVSIM_INSTANTIATE_VISIT(PoseConfig);

}  // namespace uavsim::core
