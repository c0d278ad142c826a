// Training episodes on disk (`uavsim train --data FILE`): simulate once, train
// many times. A versioned little-endian binary file; camera crops are stored
// as the 8-bit grey values they were made from (lossless).
//
// Versions (the 8-byte magic): "UAVEPS02" (written) stores each sample's
// fate and arrival time and each episode's raw modalities; "UAVEPS01"
// (read) has none of them: its samples read
// with fate kOnTime when on time, else kUnknown, and a NaN arrival time.
//
// Layout of version 02 (v01: the same without the two fields marked *):
//   magic[8], u64 episodes, then per episode:
//     string label (u64 size + bytes), f64 window_s, *u8 raw modalities
//     (Episode::raw_modalities; v01: kRawUnknown),
//     u64 K, K x vec3 window truth (vec3 = 3 x f64),
//     u64 N, N samples:
//       u8 modality, u32 node, f64 t_s, u8 on_time, *u8 fate, *f64 t_arrival_s,
//       vec3 truth, u8 kind (1 camera, 2 points), then
//       camera: f64 t_s, u8 detected, u64 n + n grey bytes (left crop), the
//               same (right crop), 6 x f32 (centre left x, y, centre right
//               x, y, side left, side right), 4 x vec3 (eye left, eye right,
//               bearing left, bearing right)
//       points: f64 t_s, i32 channels, u64 n + n x f32 values,
//               vec3 sensor position
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "pipeline/training/dataset.h"

namespace uavsim::pipeline {

// A crop's grey value as the byte stored for it (here and by `uavsim
// dataset`): round(clamp(v, 0, 1) * 255). The camera pre-processor makes its
// values from bytes (GreyFloats), so for them the byte is exact: lossless.
std::uint8_t GreyByte(float v);
// Bytes k as the camera pre-processor's floats: OpenCV's convertTo with
// scale 1 / 255 (not always the float k / 255.0f), so that a crop read back
// is bit for bit the crop that was simulated.
std::vector<float> GreyFloats(const std::uint8_t* bytes, std::size_t n);

// Writes atomically (temp file, then rename). Throws std::runtime_error
// naming the path.
void WriteEpisodes(const std::vector<Episode>& episodes, const std::string& path);
// Throws std::runtime_error naming the path for a file that cannot be
// opened, core::ConfigError (bad input) naming it for a foreign one ("not
// an episode file"), a truncated one ("truncated at byte N of M": the
// record at byte N runs past the file's M bytes) or a corrupt value.
// `check_stop` (if set) is called before each episode and may throw (a
// termination signal while a large file is read).
std::vector<Episode> ReadEpisodes(const std::string& path,
                                  const std::function<void()>& check_stop = {});

}  // namespace uavsim::pipeline
