// A run as one MCAP file (`uavsim run --record mcap`: recording.mcap in the
// run directory), in Foxglove's message types (sim/foxglove_schemas.h),
// JSON-encoded, in zstd chunks (results/mcap_writer.h). Log times are the
// simulation clock (ns since the run's start). Topics:
//
//   /world                    foxglove.SceneUpdate, once at t = 0: each static
//                             mesh as triangles (coloured by material), each
//                             node as a cube with its id, the base station
//   /tf/<frame>               foxglove.FrameTransform, parent "world": each
//                             node's body frame (REP 103) and the base station
//                             at t = 0, each camera eye's optical frame
//                             ("<node>/left", "<node>/right": z forward, x
//                             right, y down), and "uav/<id>" at each window
//   /<node>/{left,right}/image        foxglove.CompressedImage (PNG), per frame
//   /<node>/{left,right}/calibration  foxglove.CameraCalibration, at t = 0:
//                             Kannala-Brandt ("kannala_brandt", which
//                             Foxglove draws) fitted to the Mei model over
//                             the image's field of view, the fit's largest
//                             error in the channel's metadata
//   /<node>/points            foxglove.PointCloud, frame "world", float32
//                             fields: LiDAR x, y, z, intensity, t_offset_s;
//                             radar x, y, z, radial_velocity_mps, snr_db
//   /<node>/range_doppler     foxglove.CompressedImage (PNG, as recorded to
//                             frames/radar/: sensors/radar_image.h), per frame
//   /truth                    foxglove.SceneUpdate per window: each UAV's box
//                             at the window's end, posed as it flies
//   /estimates/<method>       foxglove.SceneUpdate per window the method
//                             estimated (as estimates.csv): a sphere
//   /window_error             uavsim.WindowError per window: the target's
//                             position and each estimate's error in metres
//   /uplink                   uavsim.UplinkMessage per message sent (as
//                             packets.csv), logged at its capture time,
//                             written when the run ends (its fate known then)
//
// Sensor channels carry metadata "node" and "modality". Deterministic: the
// same run gives the same bytes (no wall clock; channels made in the order
// first used, which follows the event order).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "channel/edge_receiver.h"
#include "core/json_io.h"
#include "results/mcap_writer.h"
#include "sensors/frames.h"
#include "sim/scenario.h"
#include "sim/world_model.h"

namespace uavsim::sim {

class McapRecorder {
 public:
  // Creates `path` and writes what is known at t = 0 (the world, the static
  // frames, the cameras' calibrations). `scenario` outlives the recorder.
  // Throws std::runtime_error if the file cannot be written.
  McapRecorder(const std::string& path, const Scenario& scenario, const WorldModel& world);

  // `left_png` / `right_png`: the eyes as PNG files' bytes.
  void RecordCamera(const std::string& node_id, const sensors::StereoFrame& frame,
                    const std::vector<std::uint8_t>& left_png,
                    const std::vector<std::uint8_t>& right_png);
  void RecordLidar(const std::string& node_id, const sensors::PointCloudFrame& frame);
  // `range_doppler_png`: the frame's range-Doppler map drawn as a PNG.
  void RecordRadar(const std::string& node_id, const sensors::RadarFrame& frame,
                   const std::vector<std::uint8_t>& range_doppler_png);
  // One alignment window ending at t_s: every UAV's truth and the methods'
  // estimates (world ENU, metres) that were scored.
  void RecordWindow(double t_s, const WorldModel& world,
                    const std::map<std::string, Eigen::Vector3d>& estimates);
  // The uplink's messages (channel::EdgeReceiver::log()), then the summary;
  // closes the file.
  void Finish(const std::vector<channel::MessageRecord>& uplink_log);

  const results::McapStatistics& statistics() const { return writer_.statistics(); }
  // For metrics.json's "recording": {"file", "bytes", "messages", "chunks",
  // "topics": {topic: messages}} (after Finish: the whole file).
  core::Json Summary() const;

 private:
  std::uint16_t Channel(const std::string& topic, const std::string& schema,
                        const std::map<std::string, std::string>& metadata = {});
  void Write(const std::string& topic, const std::string& schema, std::uint64_t log_time_ns,
             const core::Json& message, const std::map<std::string, std::string>& metadata = {});
  void WriteStatic(const WorldModel& world);
  void WriteCalibrations(const NodeConfig& node);

  const Scenario& scenario_;
  results::McapWriter writer_;
  std::map<std::string, std::uint16_t> schemas_, channels_;
};

}  // namespace uavsim::sim
