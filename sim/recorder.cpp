#include "sim/recorder.h"

#include <cstdio>

#include "sensors/image_io.h"
#include "sensors/ply_io.h"
#include "sensors/radar_image.h"

namespace uavsim::sim {

Recorder::Recorder(results::RunDirectory& dir, std::set<std::string> modalities)
    : dir_(dir), modalities_(std::move(modalities)) {}

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
  const std::string n = NextName("camera");
  for (const auto& [eye, image] :
       {std::pair<const char*, const sensors::GrayImage*>{"left", &frame.left},
        std::pair<const char*, const sensors::GrayImage*>{"right", &frame.right}}) {
    const std::string file = std::string("frames/camera/") + eye + "/" + n + ".png";
    const std::vector<std::uint8_t> png = sensors::EncodePng(*image);
    dir_.WriteText(file, std::string(png.begin(), png.end()));
    Index(frame.t_capture_s, node_id, file);
  }
}

void Recorder::RecordLidar(const std::string& node_id, const sensors::PointCloudFrame& frame) {
  const std::string file = "frames/lidar/" + NextName("lidar") + ".ply";
  dir_.WriteText(file, sensors::EncodePly(frame));
  Index(frame.t_start_s, node_id, file);
}

void Recorder::RecordRadar(const std::string& node_id, const sensors::RadarFrame& frame) {
  const std::string n = NextName("radar");
  const std::string ply = "frames/radar/" + n + ".ply";
  dir_.WriteText(ply, sensors::EncodePly(frame));
  Index(frame.t_capture_s, node_id, ply);
  const std::string png = "frames/radar/" + n + ".png";
  const std::vector<std::uint8_t> image = sensors::EncodeRangeDopplerPng(frame.range_doppler);
  dir_.WriteText(png, std::string(image.begin(), image.end()));
  Index(frame.t_capture_s, node_id, png);
}

void Recorder::Finish() {
  if (files_ > 0) dir_.WriteText("frames/index.csv", index_.str());
}

}  // namespace uavsim::sim
