// The FMCW radar's raw data: the complex baseband IF cube of one frame,
// ADC samples x chirps x virtual antennas (paper Sec. IV-A). Its size is the
// radar modality's raw data rate.
#pragma once

#include <complex>
#include <cstddef>
#include <vector>

namespace uavsim::sensors {

struct RadarCube {
  int samples = 0;  // ADC samples per chirp (fast time)
  int chirps = 0;   // chirps per frame (slow time)
  int nx = 0;       // virtual array columns (along the radar's y axis, see fmcw_radar.h)
  int ny = 0;       // virtual array rows (along the radar's z axis)
  // Samples are contiguous (for the range FFT); then chirps; then antennas,
  // ix fastest: index = ((iy * nx + ix) * chirps + c) * samples + s.
  std::vector<std::complex<float>> data;

  void Resize(int samples_, int chirps_, int nx_, int ny_) {
    samples = samples_, chirps = chirps_, nx = nx_, ny = ny_;
    data.assign(static_cast<std::size_t>(samples) * chirps * nx * ny, {0.0f, 0.0f});
  }
  std::size_t Index(int s, int c, int ix, int iy) const {
    return ((static_cast<std::size_t>(iy) * nx + ix) * chirps + c) * samples + s;
  }
  std::complex<float>& at(int s, int c, int ix, int iy) { return data[Index(s, c, ix, iy)]; }
  const std::complex<float>& at(int s, int c, int ix, int iy) const {
    return data[Index(s, c, ix, iy)];
  }
  std::size_t RawBytes() const { return data.size() * sizeof(std::complex<float>); }
};

}  // namespace uavsim::sensors
