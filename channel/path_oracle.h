// What the radio channel asks of the world, without seeing Embree: whether a
// straight segment is blocked, and which planar faces can reflect. The engine
// (sim/) implements it over the sensors' ray-cast scene; tests implement it
// with closed-form geometry.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/world_geometry.h"

namespace uavsim::channel {

class PathOracle {
 public:
  virtual ~PathOracle() = default;
  // True if anything blocks the straight segment from a to b (ends excluded).
  virtual bool Blocked(const Eigen::Vector3d& a_m, const Eigen::Vector3d& b_m) const = 0;
  // Planar faces that may reflect (building facades); may be empty.
  virtual const std::vector<core::Facade>& Reflectors() const = 0;
};

// Free space: nothing blocks, nothing reflects.
class FreeSpace : public PathOracle {
 public:
  bool Blocked(const Eigen::Vector3d&, const Eigen::Vector3d&) const override { return false; }
  const std::vector<core::Facade>& Reflectors() const override { return none_; }

 private:
  std::vector<core::Facade> none_;
};

}  // namespace uavsim::channel
