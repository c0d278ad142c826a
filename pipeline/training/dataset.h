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
  // The windows whose truth the part of a Dataset holding this copy may use:
  // empty, every window (a split by trajectory); else [k - 1] is 1 for the
  // windows of this part (a split by frame). Stage 1 learns from the samples
  // captured in such windows only; stage 2's losses, its validation and the
  // held-out scores count such windows only. Not stored by dataset_io.
  std::vector<std::uint8_t> scored_windows;
  // Whether window k (1-based) is scored, as above.
  bool Scored(std::int64_t k) const {
    if (scored_windows.empty()) return true;
    return k >= 1 && k <= static_cast<std::int64_t>(scored_windows.size()) &&
           scored_windows[static_cast<std::size_t>(k - 1)] != 0;
  }
};

// How a Dataset was split into training, validation and test parts.
enum class DataSplit {
  // By trajectory (the default): each episode is its own trajectory and lies
  // in one part only, 70 / 15 / 15 % with at least one episode in each part
  // when there are three or more. Held-out scores are on unseen flights.
  kTrajectory,
  // By frame (the random frame split common in the literature): every
  // episode lies in every part, each of its windows drawn into one part
  // (70 / 15 / 15 %) and scored there only (Episode::scored_windows). A
  // test window's neighbours, 0.2 s away, were training labels; its inputs
  // were seen in training, unlabelled.
  kFrame,
};
const char* DataSplitName(DataSplit s);  // "trajectory", "frame"

// The weather an episode was simulated in, from its label (sim/train.cpp
// writes ", rain N mm/h" and ", fog N m"): "clear", "rain", "fog" or
// "rain+fog".
std::string WeatherOf(const Episode& e);

struct Dataset {
  std::vector<Episode> train, validation, test;
  DataSplit split = DataSplit::kTrajectory;
};

}  // namespace uavsim::pipeline
