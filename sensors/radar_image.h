// A range-Doppler map as a PNG a person can read (recorded beside each radar
// frame's point cloud). OpenCV does the drawing and encoding; it stays
// private to sensors/, so this header shows no OpenCV type.
//
// Layout: range on the vertical axis, near range at the bottom; radial
// velocity on the horizontal axis, zero in the middle, receding (positive)
// to the right. Each map cell is drawn as a block of pixels (the plot is at
// least 512 px wide and 512 px tall for small maps); range ticks in metres on
// the left, velocity ticks in m/s below, a colour bar in dB on the right.
// Colour: viridis over the top `dynamic_range_db` of the map (the strongest
// cell is yellow, anything dynamic_range_db or more below it is dark blue).
#pragma once

#include <cstdint>
#include <vector>

#include "sensors/frames.h"

namespace uavsim::sensors {

// The bytes of a colour PNG of `map`. Non-finite cells are drawn as the
// bottom of the scale. Throws std::invalid_argument if the map is empty,
// power_db.size() is not range_bins * doppler_bins, or dynamic_range_db is
// not positive; std::runtime_error if the encoder fails.
std::vector<std::uint8_t> EncodeRangeDopplerPng(const RangeDopplerMap& map,
                                                double dynamic_range_db = 60.0);

}  // namespace uavsim::sensors
