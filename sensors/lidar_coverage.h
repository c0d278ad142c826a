// How long a LiDAR's scan pattern takes to cover its field, from the
// pattern alone (no ray is cast): what sets the length of a node's survey
// of its static surroundings (sim/lidar_survey.h).
//
// Directions are binned into cells of about cell_rad x cell_rad: rows of
// elevation cell_rad high (world frame), each row split into
// ceil(2 pi cos(el) / cell_rad) equal azimuth cells, so cells are of about
// equal solid angle. The field is the set of cells the pattern reaches in
// the frames starting at -T, -2T, ..., -K T (T = 1 / rate_hz, K frames in
// horizon_s): the scans a survey ending at t = 0 would make. The answer is
// the fewest frames, counted back from t = 0, whose beams hit `fraction` of
// the field's cells at least once. A spinning LiDAR's pattern repeats every
// frame: one frame. Deterministic (a pure function of the configuration).
#pragma once

#include <cstddef>

#include "sensors/lidar.h"

namespace uavsim::sensors {

struct LidarCoverage {
  int frames = 0;                 // the survey's length in frames
  double cell_rad = 0.0;          // the cell size used (after the floor below)
  std::size_t field_cells = 0;    // cells the pattern reaches within the horizon
  std::size_t covered_cells = 0;  // of those, hit within `frames`
};

// Cells smaller than sqrt(4 pi / kMaxCoverageCells) are raised to that size
// (a cell table of at most this many entries).
constexpr std::size_t kMaxCoverageCells = std::size_t{1} << 25;

// Throws std::invalid_argument unless cell_rad > 0, 0 < fraction <= 1 and
// horizon_s > 0.
LidarCoverage FramesToCover(const Lidar& lidar, double cell_rad, double fraction, double horizon_s);

}  // namespace uavsim::sensors
