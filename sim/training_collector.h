// Training data from a run (sim/train.h): observes the sensing nodes' frames,
// the edge's on-time arrivals and the windows' ends, and fills an Episode
// (pipeline/training/dataset.h): every frame whose pre-processing found
// something, with the truth at its capture time and whether it reached the
// edge in time, and the truth at every window's end up to the run's end.
#pragma once

#include "pipeline/training/dataset.h"
#include "sim/core/time.h"
#include "sim/sensing_node.h"
#include "sim/world_model.h"

namespace uavsim::sim {

class TrainingCollector {
 public:
  // Clears `episode` and sets its window; both references outlive the collector.
  TrainingCollector(pipeline::Episode& episode, const WorldModel& world, double window_s,
                    core::SimTime t_end);

  // A node's frame that found something (tags `content` with its sample).
  void OnFrame(const SensingNode& node, double t_s, NodeContent& content);
  // A message that arrived on time with `content`.
  void OnArrival(const NodeContent& content);
  // A window's deadline passed; the window ended at t_window_end.
  void OnWindow(core::SimTime t_window_end, const Eigen::Vector3d& truth_m);

 private:
  pipeline::Episode& episode_;
  const WorldModel& world_;
  core::SimTime t_end_;
};

}  // namespace uavsim::sim
