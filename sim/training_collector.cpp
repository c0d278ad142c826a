#include "sim/training_collector.h"

namespace uavsim::sim {

TrainingCollector::TrainingCollector(pipeline::Episode& episode, const WorldModel& world,
                                     double window_s, core::SimTime t_end)
    : episode_(episode), world_(world), t_end_(t_end) {
  episode_.window_s = window_s;
  episode_.samples.clear();
  episode_.window_truth.clear();
}

void TrainingCollector::OnFrame(const SensingNode& node, double t_s, NodeContent& content) {
  pipeline::Sample sample;
  sample.modality = node.modality();
  sample.node = node.index();
  sample.t_s = t_s;
  // Labelled at the observation's own time stamp (a LiDAR sweep's: when the
  // kept points were swept), where the target was when it was seen.
  const double t_seen_s = content.points ? content.points->t_s : content.camera->t_s;
  sample.truth_m = world_.target().StateAt(t_seen_s).position_m;
  sample.camera = content.camera;
  sample.points = content.points;
  content.sample = episode_.samples.size();
  episode_.samples.push_back(std::move(sample));
}

void TrainingCollector::OnArrival(const NodeContent& content, double t_arrival_s, bool on_time) {
  if (!content.Found()) return;  // the picked observation is the sample
  pipeline::Sample& sample = episode_.samples[content.sample];
  if (on_time) sample.on_time = true;
  sample.fate = on_time ? pipeline::SampleFate::kOnTime : pipeline::SampleFate::kLate;
  sample.t_arrival_s = t_arrival_s;
}

void TrainingCollector::OnLost(const NodeContent& content) {
  if (!content.Found()) return;  // the picked observation is the sample
  episode_.samples[content.sample].fate = pipeline::SampleFate::kLost;
}

void TrainingCollector::OnWindow(core::SimTime t_window_end, const Eigen::Vector3d& truth_m) {
  if (t_window_end <= t_end_) episode_.window_truth.push_back(truth_m);
}

}  // namespace uavsim::sim
