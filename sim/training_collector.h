// Training data from a run (apps/train/train.h): observes the sensing nodes' frames,
// every message's fate at the edge (on time, late, lost) and the windows'
// ends, and fills an Episode (pipeline/training/dataset.h): every frame whose
// pre-processing found something, with the truth at the observation's own time stamp, when
// and whether it reached the edge, and the truth at every window's end up to
// the run's end. A sample whose message is neither arrived nor lost when the
// run ends keeps the fate kInFlight and no arrival time.
#pragma once

#include "core/time.h"
#include "pipeline/training/dataset.h"
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
  // A message with `content` arrived at the edge at t_arrival_s (simulated
  // seconds), by its window's deadline (`on_time`, as the edge decided) or
  // after it. Messages that carry nothing are ignored.
  void OnArrival(const NodeContent& content, double t_arrival_s, bool on_time);
  // A message with `content` was lost on the uplink.
  void OnLost(const NodeContent& content);
  // A window's deadline passed; the window ended at t_window_end.
  void OnWindow(core::SimTime t_window_end, const Eigen::Vector3d& truth_m);

 private:
  pipeline::Episode& episode_;
  const WorldModel& world_;
  core::SimTime t_end_;
};

}  // namespace uavsim::sim
