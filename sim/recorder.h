// Writes raw sensor frames into a run directory (`uavsim run --record`):
// frames/camera/{left,right}/NNNNNN.png, frames/lidar/NNNNNN.ply,
// frames/radar/NNNNNN.ply with its range-Doppler map frames/radar/NNNNNN.png,
// and frames/index.csv (t_s,sensor,file), numbered
// per modality in capture order. Files go through the run directory's
// staging, so a failed run leaves none of them under the final name.
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>

#include "results/csv.h"
#include "results/run_directory.h"
#include "sensors/frames.h"

namespace uavsim::sim {

class Recorder {
 public:
  // `modalities`: any of "camera", "lidar", "radar".
  Recorder(results::RunDirectory& dir, std::set<std::string> modalities);

  bool Wants(const std::string& modality) const { return modalities_.count(modality) > 0; }

  void RecordCamera(const std::string& node_id, const sensors::StereoFrame& frame);
  void RecordLidar(const std::string& node_id, const sensors::PointCloudFrame& frame);
  // frames/radar/NNNNNN.ply (detections) and frames/radar/NNNNNN.png (its
  // range-Doppler map in dB).
  void RecordRadar(const std::string& node_id, const sensors::RadarFrame& frame);

  // Writes frames/index.csv (if anything was recorded).
  void Finish();

  std::uint64_t files_written() const { return files_; }

 private:
  std::string NextName(const std::string& modality);
  void Index(double t_s, const std::string& node_id, const std::string& file);

  results::RunDirectory& dir_;
  std::set<std::string> modalities_;
  std::map<std::string, std::uint64_t> counters_;
  results::CsvTable index_{{"t_s", "sensor", "file"}};
  std::uint64_t files_ = 0;
};

}  // namespace uavsim::sim
