// One observation a node sent that reached the edge on time, as the
// multi-target methods see it (issue 46): every observation of a message,
// the one its pre-processing picked and the further ones
// (/pipeline/preprocess/max_observations). World ENU, metres, seconds.
#pragma once

#include <cstdint>
#include <vector>

#include "core/modality.h"
#include "pipeline/anchored/geometric_anchor.h"

namespace uavsim::pipeline {

struct Detection {
  core::Modality modality = core::Modality::kCamera;
  std::uint32_t node = 0;     // the node's index in /nodes
  double t_capture_s = 0.0;   // the message's capture stamp (one per message)
  GeometricAnchor anchor;     // never kNone; its t_s is the capture time
  std::vector<float> latent;  // the IB-CC mu (empty without a model)
};

// A labelled position: a tracker's confirmed track at a window's end.
struct TrackEstimate {
  std::uint32_t track = 0;  // 1, 2, ... in the order tracks were born
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
};

}  // namespace uavsim::pipeline
