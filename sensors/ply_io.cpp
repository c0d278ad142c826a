#include "sensors/ply_io.h"

#include <cstdint>
#include <cstring>
#include <sstream>

namespace uavsim::sensors {
namespace {

void AppendFloatLe(std::string& out, float v) {
  std::uint32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  for (int k = 0; k < 4; ++k) out.push_back(static_cast<char>((bits >> (8 * k)) & 0xFFu));
}

}  // namespace

std::string EncodePly(const RadarFrame& frame) {
  std::ostringstream header;
  header.precision(17);
  header << "ply\n"
         << "format binary_little_endian 1.0\n"
         << "comment uavsim radar frame, world frame ENU metres, radial velocity m/s, snr dB\n"
         << "comment t_capture_s " << frame.t_capture_s << "\n"
         << "element vertex " << frame.points.size() << "\n"
         << "property float x\n"
         << "property float y\n"
         << "property float z\n"
         << "property float velocity\n"
         << "property float snr\n"
         << "end_header\n";
  std::string out = header.str();
  for (const RadarPoint& p : frame.points) {
    AppendFloatLe(out, p.x_m);
    AppendFloatLe(out, p.y_m);
    AppendFloatLe(out, p.z_m);
    AppendFloatLe(out, p.radial_velocity_mps);
    AppendFloatLe(out, p.snr_db);
  }
  return out;
}

std::string EncodePly(const PointCloudFrame& frame) {
  std::ostringstream header;
  header.precision(17);
  header << "ply\n"
         << "format binary_little_endian 1.0\n"
         << "comment uavsim lidar frame, world frame ENU metres, t in s after t_start_s\n"
         << "comment t_start_s " << frame.t_start_s << "\n"
         << "element vertex " << frame.points.size() << "\n"
         << "property float x\n"
         << "property float y\n"
         << "property float z\n"
         << "property float intensity\n"
         << "property float t\n"
         << "end_header\n";
  std::string out = header.str();
  out.reserve(out.size() + frame.points.size() * 5 * sizeof(float));
  for (const LidarPoint& p : frame.points) {
    AppendFloatLe(out, p.x_m);
    AppendFloatLe(out, p.y_m);
    AppendFloatLe(out, p.z_m);
    AppendFloatLe(out, p.intensity);
    AppendFloatLe(out, p.t_offset_s);
  }
  return out;
}

}  // namespace uavsim::sensors
