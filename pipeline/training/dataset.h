// Training data for UAVLoc as the simulator produces it (plain data, torch-
// free): per episode (one trajectory, one seed, one weather and loss draw)
// every pre-processed observation a sensing node produced, with the truth at
// its capture time and its fate on the uplink, and the truth at the end of
// every alignment window. Stage 1 (IB-CC) learns from the observations, stage
// 2 (fusion and Mamba) from the windows of on-time latents.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/node/observations.h"

namespace uavsim::pipeline {

// One node frame whose pre-processing found something to send.
struct Sample {
  Modality modality = Modality::kCamera;
  std::uint32_t node = 0;  // index of the node in its scenario
  double t_s = 0.0;        // capture time
  bool on_time = false;    // arrived at the edge before its window's deadline
  Eigen::Vector3d truth_m = Eigen::Vector3d::Zero();  // target position at t_s
  std::optional<CameraObservation> camera;            // set for the camera
  std::optional<PointObservation> points;             // set for LiDAR and radar
};

struct Episode {
  std::string label;  // what varied, for reports: "orbit seed 7 rain 4 mm/h loss 0.12"
  double window_s = 0.2;
  std::vector<Sample> samples;                // in capture order
  std::vector<Eigen::Vector3d> window_truth;  // [k - 1]: target position at k t^w
};

// Episodes split by trajectory (each episode is its own trajectory), never by
// frame: 70 / 15 / 15 % with at least one episode in each part when there are
// three or more.
struct Dataset {
  std::vector<Episode> train, validation, test;
};

}  // namespace uavsim::pipeline
