// Writes what a run records (`uavsim run --record LIST`) into its run
// directory. Raw sensor frames, per modality named in LIST:
// frames/camera/{left,right}/NNNNNN.png, frames/lidar/NNNNNN.ply,
// frames/radar/NNNNNN.ply with its range-Doppler map frames/radar/NNNNNN.png,
// and frames/index.csv (t_s,sensor,file), numbered per modality in capture
// order. With "mcap" in LIST: recording.mcap, every sensor's frames, the
// world, the truth, the estimates and the uplink in one file
// (sim/mcap_recorder.h). Files go through the run directory's staging, so a
// failed run leaves none of them under the final name.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "channel/edge_receiver.h"
#include "results/csv.h"
#include "results/run_directory.h"
#include "sensors/frames.h"
#include "sim/mcap_recorder.h"

namespace uavsim::sim {

class Recorder {
 public:
  // `modalities`: any of "camera", "lidar", "radar" and "mcap". With "mcap"
  // `scenario` and `world` (which outlive the recorder) give the
  // recording's world and truth, and recording.mcap is created now.
  Recorder(results::RunDirectory& dir, std::set<std::string> modalities, const Scenario& scenario,
           const WorldModel& world);

  // Whether frames of `modality` are recorded (as files, in the MCAP or both).
  bool Wants(const std::string& modality) const {
    return mcap_.has_value() || modalities_.count(modality) > 0;
  }

  void RecordCamera(const std::string& node_id, const sensors::StereoFrame& frame);
  void RecordLidar(const std::string& node_id, const sensors::PointCloudFrame& frame);
  // frames/radar/NNNNNN.ply (detections) and frames/radar/NNNNNN.png (its
  // range-Doppler map in dB).
  void RecordRadar(const std::string& node_id, const sensors::RadarFrame& frame);
  // An alignment window's truth and scored estimates (MCAP only).
  void RecordWindow(double t_s, const WorldModel& world,
                    const std::map<std::string, Eigen::Vector3d>& estimates);

  // Writes frames/index.csv (if any frame file was recorded) and closes
  // recording.mcap with the uplink's messages.
  void Finish(const std::vector<channel::MessageRecord>& uplink_log);

  std::uint64_t files_written() const { return files_; }
  bool records_mcap() const { return mcap_.has_value(); }
  // recording.mcap's McapRecorder::Summary(), or null without "mcap".
  core::Json McapSummary() const { return mcap_ ? mcap_->Summary() : core::Json(nullptr); }

 private:
  bool WantsFiles(const std::string& modality) const { return modalities_.count(modality) > 0; }
  std::string NextName(const std::string& modality);
  void Index(double t_s, const std::string& node_id, const std::string& file);

  results::RunDirectory& dir_;
  std::set<std::string> modalities_;
  std::optional<McapRecorder> mcap_;
  std::map<std::string, std::uint64_t> counters_;
  results::CsvTable index_{{"t_s", "sensor", "file"}};
  std::uint64_t files_ = 0;
};

}  // namespace uavsim::sim
