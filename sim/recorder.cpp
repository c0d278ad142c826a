#include "sim/recorder.h"

#include <cstdio>

#include "sensors/image_io.h"
#include "sensors/ply_io.h"
#include "sensors/radar_image.h"

namespace uavsim::sim {

Recorder::Recorder(results::RunDirectory& dir, std::set<std::string> modalities,
                   const Scenario& scenario, const WorldModel& world)
    : dir_(dir), modalities_(std::move(modalities)) {
  if (modalities_.erase("mcap")) mcap_.emplace(dir_.StagingPath("recording.mcap"), scenario, world);
}

std::string Recorder::NextName(const std::string& modality) {
  char name[32];
  std::snprintf(name, sizeof name, "%06llu",
                static_cast<unsigned long long>(counters_[modality]++));
  return name;
}

void Recorder::Index(double t_s, const std::string& node_id, const std::string& file) {
  index_.AddRow({results::FormatFixed(t_s, 6), node_id, file});
  ++files_;
}

void Recorder::RecordCamera(const std::string& node_id, const sensors::StereoFrame& frame) {
  const std::vector<std::uint8_t> left = sensors::EncodePng(frame.left);
  const std::vector<std::uint8_t> right = sensors::EncodePng(frame.right);
  if (mcap_) mcap_->RecordCamera(node_id, frame, left, right);
  if (!WantsFiles("camera")) return;
  const std::string n = NextName("camera");
  for (const auto& [eye, png] :
       {std::pair<const char*, const std::vector<std::uint8_t>*>{"left", &left},
        std::pair<const char*, const std::vector<std::uint8_t>*>{"right", &right}}) {
    const std::string file = std::string("frames/camera/") + eye + "/" + n + ".png";
    dir_.WriteText(file, std::string(png->begin(), png->end()));
    Index(frame.t_capture_s, node_id, file);
  }
}

void Recorder::RecordLidar(const std::string& node_id, const sensors::PointCloudFrame& frame) {
  if (mcap_) mcap_->RecordLidar(node_id, frame);
  if (!WantsFiles("lidar")) return;
  const std::string file = "frames/lidar/" + NextName("lidar") + ".ply";
  dir_.WriteText(file, sensors::EncodePly(frame));
  Index(frame.t_start_s, node_id, file);
}

void Recorder::RecordRadar(const std::string& node_id, const sensors::RadarFrame& frame) {
  const std::vector<std::uint8_t> image = sensors::EncodeRangeDopplerPng(frame.range_doppler);
  if (mcap_) mcap_->RecordRadar(node_id, frame, image);
  if (!WantsFiles("radar")) return;
  const std::string n = NextName("radar");
  const std::string ply = "frames/radar/" + n + ".ply";
  dir_.WriteText(ply, sensors::EncodePly(frame));
  Index(frame.t_capture_s, node_id, ply);
  const std::string png = "frames/radar/" + n + ".png";
  dir_.WriteText(png, std::string(image.begin(), image.end()));
  Index(frame.t_capture_s, node_id, png);
}

void Recorder::RecordWindow(double t_s, const WorldModel& world,
                            const std::map<std::string, Eigen::Vector3d>& estimates) {
  if (mcap_) mcap_->RecordWindow(t_s, world, estimates);
}

void Recorder::Finish(const std::vector<channel::MessageRecord>& uplink_log) {
  if (files_ > 0) dir_.WriteText("frames/index.csv", index_.str());
  if (mcap_) mcap_->Finish(uplink_log);
}

}  // namespace uavsim::sim
