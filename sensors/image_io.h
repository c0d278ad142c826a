// Image encoding for recorded frames (frames/camera/{left,right}/NNNNNN.png).
// OpenCV's imgcodecs does the work; it stays private to sensors/, so this
// header shows no OpenCV type.
#pragma once

#include <cstdint>
#include <vector>

#include "sensors/frames.h"

namespace uavsim::sensors {

// Lossless 8-bit greyscale PNG of `image`, as the bytes of a .png file.
// Throws std::invalid_argument if the image is empty or pixels.size() is not
// width * height, std::runtime_error if the encoder fails.
std::vector<std::uint8_t> EncodePng(const GrayImage& image);

}  // namespace uavsim::sensors
