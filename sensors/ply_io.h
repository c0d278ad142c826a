// Point clouds as PLY files (Turk 1994; the format of Paul Bourke's
// specification that MeshLab, CloudCompare, Open3D and PCL read).
#pragma once

#include <string>

#include "sensors/frames.h"

namespace uavsim::sensors {

// A LiDAR frame as a binary little-endian PLY 1.0 file: one `vertex`
// element per point with float32 properties x, y, z (world frame, ENU
// metres), intensity ([0, 1]) and t (seconds after the frame's start; the
// start itself is in a `comment t_start_s ...` header line, since float32
// cannot hold absolute times to the microsecond). Header lines end in '\n'.
// The bytes are little-endian on any host; the result is the whole file.
std::string EncodePly(const PointCloudFrame& frame);

// A radar frame's detections, likewise: float32 x, y, z (world frame, ENU
// metres), velocity (radial, m/s, positive receding) and snr (dB); the
// capture time in a `comment t_capture_s ...` line.
std::string EncodePly(const RadarFrame& frame);

}  // namespace uavsim::sensors
