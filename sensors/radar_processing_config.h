// The radar sensing node's signal processing parameters (issue 4 item 4):
// windows, static-clutter removal, 2-D CA-CFAR, angle estimation. The
// processing itself, and the formulas these keys enter, are in
// sensors/radar_processor.h.
//
// Rules that involve the waveform (the CFAR window must fit the chirps and
// the samples; sources per detection must be fewer than the array's
// elements) are checked by RadarProcessor's constructor, which throws
// std::invalid_argument naming the key.
#pragma once

namespace uavsim::sensors {

enum class AngleMethod { kMusic, kEsprit, kBeamscan };

// Taper applied before each FFT (DFT-even forms, Harris 1978).
enum class RadarWindow { kHann, kHamming, kBlackman, kRectangular };

// How many sources the subspace methods look for in one detection cell.
enum class SourceCount {
  kOne,  // one: a UAV at tens of metres is far below the array's angular resolution
  kMdl,  // Wax & Kailath's minimum description length, capped at max_sources
};

struct RadarProcessingConfig {
  AngleMethod angle_method = AngleMethod::kMusic;
  bool clutter_removal = true;  // subtract the (windowed) mean over chirps: zero-Doppler notch
  RadarWindow range_window = RadarWindow::kHann;
  RadarWindow doppler_window = RadarWindow::kHann;
  // 2-D cell-averaging CFAR on the range-Doppler map: a rectangle of
  // guard cells around the cell under test, then training cells beyond it,
  // on each side, per axis.
  int cfar_guard_range_cells = 2;
  int cfar_guard_doppler_cells = 2;
  int cfar_training_range_cells = 8;
  int cfar_training_doppler_cells = 4;
  double cfar_pfa = 1e-5;  // per cell, on thermal noise: 0.3 false alarms per 512 x 64 map
  // Range and Doppler of a detection from a parabola through the log power
  // of the peak and its two neighbours (else the bin centre).
  bool interpolate_peaks = true;
  int max_detections = 256;  // per frame, strongest first
  // Snapshots for the spatial covariance: the cells within this many bins
  // (range and Doppler) of the detection, plus forward-backward averaging.
  int snapshot_neighbourhood_cells = 1;
  bool forward_backward = true;
  SourceCount source_count = SourceCount::kOne;
  int max_sources = 2;  // with source_count "mdl"
  // MUSIC's coarse search grid over the field of view; each peak is then
  // refined by a pattern search to 0.005 deg. Keep it well under the
  // array's beamwidth, about 2 / N rad (29 deg for the default 4 columns).
  double music_grid_step_deg = 4.0;
  // Beamscan: 2-D FFT of the detection cell's snapshot, zero-padded to this
  // size per axis (at least the array's size), peak bin without refinement.
  int beamscan_fft_size = 64;
};

template <class V>
void Visit(V& v, RadarProcessingConfig& c);

}  // namespace uavsim::sensors
