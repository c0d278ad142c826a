// The radar sensing node's pre-processing (paper Sec. IV-A; issue 4 item 4):
// IF cube -> range-Doppler map -> 2-D CA-CFAR -> angle per detection ->
// point cloud (x, y, z, radial velocity, SNR) in the world frame. The cube's
// size is the modality's raw data, the points its pre-processed data.
//
// Conventions are those of sensors/fmcw_radar.h (radar frame R, virtual array
// element (ix, iy) at (0, ix dx, iy dy), direction
// u = (cos el cos az, cos el sin az, sin el), phase model). The chain, per
// frame of Ns samples, Nc chirps and M = nx * ny antennas:
//  1. Range FFT per chirp and antenna of the windowed samples: bin k is the
//     beat frequency k fs / Ns, range R = k * range_bin_m with
//     range_bin_m = c fs / (2 K Ns) = c / (2 B_s), B_s = K Ns / fs the
//     bandwidth swept while the ADC samples (768 MHz, 0.195 m at the
//     defaults; c / 2B = 0.167 m would need the ADC to sample the whole
//     chirp). All Ns bins are kept: complex sampling makes beat frequencies
//     in [0, fs) unambiguous, so the maximum range is fs c / (2 K).
//  2. Static-clutter removal (config.clutter_removal): per range bin and
//     antenna, the mean over chirps weighted by the Doppler window is
//     subtracted. Whatever does not move is removed exactly; the zero-Doppler
//     bin becomes 0, the bins next to it change (+-1 with Hann), the others
//     are untouched. (A plain mean removes static scatterers as well, but
//     each off-bin mover leaks into it by sin(pi f) / (pi f), -30 dB at 10
//     bins, and its subtraction paints a false target at zero Doppler.)
//  3. Doppler FFT per range bin and antenna of the windowed chirps,
//     fftshifted: Doppler bin d (0 .. Nc - 1) has radial velocity
//     (d - floor(Nc / 2)) * velocity_bin_mps, velocity_bin_mps =
//     lambda / (2 Nc T_c); positive = receding, as the synthesis makes it.
//     Unambiguous within +-lambda / (4 T_c) (12.2 m/s at the defaults).
//  4. Range-Doppler map: |X|^2 summed over antennas (non-coherently) and
//     divided by the mean thermal-noise power of that sum for unit noise
//     per ADC sample (the cube's normalisation): M sum(w_r^2) sum(w_d^2),
//     and near zero Doppler, with clutter removal, the notch's lower value
//     (computed exactly per Doppler bin). Noise-only cells average 1 (0 dB)
//     everywhere. RadarFrame::range_doppler holds it in dB.
//  5. 2-D CA-CFAR: a cell is detected when its power exceeds alpha times the
//     mean of N training cells (a rectangle of guard cells excluded around
//     it; Doppler wraps around; cells too close to the range ends for a full
//     window are not tested, nor is the empty zero-Doppler bin left by
//     clutter removal, which is also left out of the training cells, N
//     shrinking next to it). The noise-only cell is a sum of M exponentials
//     (Gamma(M)) and the training sum, whose cells the windows correlate,
//     is taken as Gamma with the same mean and variance (shape a, scale
//     theta); then, with beta = alpha / N,
//       Pfa = sum_{k=0}^{M-1} Gamma(a + k) / (Gamma(a) k!)
//             (beta theta)^k / (1 + beta theta)^(a + k)
//     (Richards, Fundamentals of Radar Signal Processing, 2nd ed., Sec. 7.4
//     and 6.3, with the moment match), solved for alpha at config.cfar_pfa.
//     For M = 1 and uncorrelated cells (a = N, theta = 1) this is the
//     classical alpha = N (Pfa^(-1/N) - 1).
//  6. Local maxima only (each detection at least its 8 neighbours), the
//     strongest config.max_detections kept; range and Doppler refined by a
//     parabola through the log power (config.interpolate_peaks).
//  7. Angle per detection from the M antenna values of the detection cell
//     and its neighbours (the snapshots):
//     - MUSIC: spatial covariance R = (1/K) sum x x^H over the K cells within
//       snapshot_neighbourhood_cells bins, forward-backward averaged
//       (R + J conj(R) J) / 2; the pseudospectrum 1 / ||E_n^H a(az, el)||^2
//       is searched on a grid over the field of view (front hemisphere:
//       the planar array cannot tell front from back) and each peak refined.
//       On one snapshot of one source at high SNR its error meets the
//       Cramer-Rao bound (tested).
//     - ESPRIT (LS, 2-D): shift invariance between the subarrays ix = 0..nx-2
//       and 1..nx-1 gives exp(j 2 pi dx u_y / lambda), between iy = 0..ny-2
//       and 1..ny-1 exp(j 2 pi dy u_z / lambda); the two are paired by the
//       eigenvectors of Psi_x + gamma Psi_y.
//     - Beamscan: peak of the zero-padded 2-D FFT of the detection cell's
//       snapshot over the visible region (the grid limits its accuracy);
//       also the fallback when a subspace method fails or returns a
//       direction outside the visible region.
//     ESPRIT and the beamscan read direction cosines from phases, which is
//     unambiguous for spacings up to lambda / 2 (the default); with wider
//     spacings they return the principal value, and only MUSIC, whose grid
//     stays in the field of view, avoids the grating lobes.
//     A single detection cell gives a rank-1 covariance. Spatial smoothing
//     would cost aperture a 4 x 3 array cannot spare; the neighbouring cells
//     are further looks at the same scatterers through the windows'
//     mainlobes, with different complex weights for scatterers at slightly
//     different range or velocity, and forward-backward averaging
//     decorrelates a coherent pair on the centro-symmetric array; both keep
//     the full aperture.
//     Sources per detection: one, or MDL (Wax & Kailath, IEEE TASSP 33(2),
//     1985) on R's eigenvalues with the snapshots' effective number: the
//     windows correlate neighbouring cells, so the 9 cells of a 3 x 3
//     neighbourhood count as 3.5 independent ones with Hann.
//  8. Point: p_R = R u(az, el), p_W = X_WR p_R; radial velocity from the
//     Doppler bin; snr_db = 10 log10(cell power / CFAR noise estimate), the
//     integrated (post-FFT) ratio as radar firmware reports it. Points come
//     strongest detection first.
// With source_count "mdl" a detection may give several points (one per
// source), all with its range, velocity and SNR.
//
// Thread safety: the FFTW plans are made once, in the constructor, under a
// lock (FFTW's planner is not thread-safe; this is the library's only FFTW
// user), with FFTW_ESTIMATE so that the plan, hence every rounding, is the
// same on every run. All const methods may run concurrently; Process uses
// one thread. Deterministic: no randomness, same cube -> same frame.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <vector>

#include "sensors/fmcw_radar_config.h"
#include "sensors/frames.h"
#include "sensors/radar_cube.h"

namespace uavsim::sensors {

// Direction of arrival in the radar frame (fmcw_radar.h), radians.
struct AngleOfArrival {
  double azimuth_rad = 0.0;
  double elevation_rad = 0.0;
};

// Storage aligned for FFTW's SIMD code, so it can transform in place.
template <class T>
struct FftAlignedAllocator {
  using value_type = T;
  static constexpr std::align_val_t kAlignment{64};
  FftAlignedAllocator() = default;
  template <class U>
  FftAlignedAllocator(const FftAlignedAllocator<U>&) {}
  T* allocate(std::size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), kAlignment)); }
  void deallocate(T* p, std::size_t) { ::operator delete(p, kAlignment); }
  template <class U>
  bool operator==(const FftAlignedAllocator<U>&) const {
    return true;
  }
  template <class U>
  bool operator!=(const FftAlignedAllocator<U>&) const {
    return false;
  }
};
using FftBuffer = std::vector<std::complex<float>, FftAlignedAllocator<std::complex<float>>>;

// Per-antenna range-Doppler spectra of one frame (steps 1-4).
struct RangeDopplerCube {
  int range_bins = 0;
  int doppler_bins = 0;  // fftshifted: zero velocity at doppler_bins / 2
  int antennas = 0;      // element iy * nx + ix, as in RadarCube
  // index = (antenna * doppler_bins + d) * range_bins + r
  FftBuffer spectra;
  // Non-coherent sum over antennas, noise-normalised (step 4), linear;
  // index = d * range_bins + r.
  std::vector<float> power;

  std::complex<float> at(int r, int d, int antenna) const {
    return spectra[(static_cast<std::size_t>(antenna) * doppler_bins + d) * range_bins + r];
  }
  float power_at(int r, int d) const { return power[static_cast<std::size_t>(d) * range_bins + r]; }
};

// CA-CFAR on a power map (step 5), index = d * range_bins + r.
struct CfarResult {
  std::vector<std::uint8_t> detected;  // 1 where power > alpha * noise
  std::vector<float> noise;            // training-cell mean; 0 where not tested
  std::size_t cells_tested = 0;
};

// A CFAR detection that is a local maximum (step 6).
struct RadarDetection {
  int range_bin = 0;
  int doppler_bin = 0;   // in the fftshifted map
  double range_m = 0.0;  // interpolated if config.interpolate_peaks
  double radial_velocity_mps = 0.0;
  double power = 0.0;   // noise-normalised cell power
  double noise = 0.0;   // CFAR noise estimate, same units
  double snr_db = 0.0;  // 10 log10(power / noise)
};

class RadarProcessor {
 public:
  // Throws std::invalid_argument, naming the key, if the CFAR window does
  // not fit the frame (2 (guard + training) + 1 must not exceed
  // chirps_per_frame in Doppler nor adc_samples in range) or the array
  // cannot hold the sources asked for.
  explicit RadarProcessor(const FmcwRadarConfig& config);
  ~RadarProcessor();
  RadarProcessor(const RadarProcessor&) = delete;
  RadarProcessor& operator=(const RadarProcessor&) = delete;

  // The whole chain. `X_WR` poses the radar in the world; t_capture_s is
  // the frame's start. Throws std::invalid_argument if the cube's shape is
  // not the config's, core::Interrupted on a termination request (polled per
  // detection). frame.scatterers is left 0 (the caller knows it).
  RadarFrame Process(const RadarCube& cube, const Eigen::Isometry3d& X_WR,
                     double t_capture_s) const;

  // --- The steps, for tests and inspection. ---

  // Step 1 only: the cube with its fast-time axis replaced by range bins.
  RadarCube RangeProfiles(const RadarCube& cube) const;
  // Steps 1-4.
  RangeDopplerCube Transform(const RadarCube& cube) const;
  // Step 5 on a power map of range_bins() x doppler_bins().
  CfarResult Cfar(const std::vector<float>& power) const;
  // Steps 5-6, strongest first.
  std::vector<RadarDetection> Detect(const RangeDopplerCube& rd) const;
  // The snapshots of a detection: M x K, one column per cell of its
  // neighbourhood, the detection cell first.
  Eigen::MatrixXcd Snapshots(const RangeDopplerCube& rd, const RadarDetection& det) const;
  // Step 7 on given snapshots (M x K, element iy * nx + ix). The subspace
  // methods return up to `sources` directions (fewer if they fail or find
  // fewer peaks); EstimateAngles applies config's method, source count and
  // the beamscan fallback and always returns at least one direction.
  std::vector<AngleOfArrival> EstimateAngles(const Eigen::MatrixXcd& snapshots) const;
  std::vector<AngleOfArrival> Music(const Eigen::MatrixXcd& snapshots, int sources) const;
  std::vector<AngleOfArrival> Esprit(const Eigen::MatrixXcd& snapshots, int sources) const;
  AngleOfArrival Beamscan(const Eigen::VectorXcd& snapshot) const;
  // The number of sources config.source_count gives for these snapshots
  // (a full neighbourhood from Snapshots counts with its effective degrees
  // of freedom, other snapshots as independent).
  int SourceCountOf(const Eigen::MatrixXcd& snapshots) const;
  // Forward-backward averaged (if configured) sample covariance.
  Eigen::MatrixXcd Covariance(const Eigen::MatrixXcd& snapshots) const;

  // The array response a(az, el): element iy * nx + ix is
  // exp(j 2 pi (ix dx u_y + iy dy u_z) / lambda).
  Eigen::VectorXcd Steering(const AngleOfArrival& direction) const;

  int range_bins() const { return samples_; }
  int doppler_bins() const { return chirps_; }
  double range_bin_m() const { return range_bin_m_; }
  double velocity_bin_mps() const { return velocity_bin_mps_; }
  double wavelength_m() const { return lambda_m_; }
  // CFAR away from zero Doppler: N, the training sum's Gamma shape a and
  // scale theta, and alpha. (Next to the clutter notch, whose zero-Doppler
  // row holds no noise and is left out, N is smaller and alpha follows.)
  int cfar_training_cells() const { return cfar_full_.training_cells; }
  double cfar_training_shape() const { return cfar_full_.shape; }
  double cfar_training_scale() const { return cfar_full_.scale; }
  double cfar_threshold_factor() const { return cfar_full_.alpha; }
  const FmcwRadarConfig& config() const { return config_; }

  // The CA-CFAR false-alarm probability above for threshold factor alpha,
  // N training cells whose sum is Gamma(shape, scale) and a cell under test
  // that sums `integrated` exponentials.
  static double CaCfarPfa(double alpha, int training_cells, double shape, double scale,
                          int integrated);
  // Its inverse in alpha (bisection on the monotone Pfa).
  static double CaCfarThresholdFactor(double pfa, int training_cells, double shape, double scale,
                                      int integrated);
  // The DFT-even window of `n` points.
  static std::vector<double> Window(RadarWindow type, int n);

 private:
  struct Fft;  // FFTW plans (FFTW stays private to sensors/)

  // The constructor's calibration, in order: the frame's shape and the
  // checks on it; wavelength, spacings and bin sizes; the windows (wr in
  // range, wd in Doppler); step 4's noise scale per Doppler bin (returns
  // which bins hold noise); step 5's CFAR rows; MUSIC's grid; the FFTW plans.
  void CheckShape();
  void DeriveBinSizes();
  void MakeWindows(const std::vector<double>& wr, const std::vector<double>& wd);
  std::vector<bool> MakeNoiseScale(const std::vector<double>& wr, const std::vector<double>& wd);
  void MakeCfarRows(const std::vector<double>& wr, const std::vector<double>& wd,
                    const std::vector<bool>& has_noise);
  void MakeMusicGrid();
  void PlanFfts();

  void TransformInto(const RadarCube& cube, RangeDopplerCube& rd) const;
  void CheckCube(const RadarCube& cube) const;
  AngleOfArrival FromDirectionCosines(double u_y, double u_z) const;
  double MusicSpectrum(const Eigen::MatrixXcd& signal_subspace, double az_rad, double el_rad) const;

  FmcwRadarConfig config_;
  int samples_ = 0, chirps_ = 0, nx_ = 0, ny_ = 0, antennas_ = 0;
  double lambda_m_ = 0.0, dx_m_ = 0.0, dy_m_ = 0.0;
  double range_bin_m_ = 0.0, velocity_bin_mps_ = 0.0;
  std::vector<float> range_window_;
  std::vector<std::complex<float>> doppler_weights_;  // window x fftshift modulation
  std::vector<float> mean_weights_;                   // window / its sum (clutter removal)
  std::vector<float> power_scale_;  // per Doppler bin: 1 / its noise power (step 4)
  // CFAR
  int cfar_half_range_ = 0, cfar_half_doppler_ = 0;
  struct CfarRow {
    bool tested = false;
    int training_cells = 0;
    double shape = 0.0, scale = 1.0, alpha = 1.0;
  };
  std::vector<CfarRow> cfar_rows_;  // per Doppler bin
  CfarRow cfar_full_;
  double snapshot_dof_ = 1.0;  // of a full neighbourhood's covariance (MDL)
  // MUSIC coarse grid
  std::vector<AngleOfArrival> grid_;
  int grid_az_ = 0, grid_el_ = 0;   // grid_[iel * grid_az_ + iaz]
  Eigen::MatrixXcd grid_steering_;  // grid points x antennas: a^H per row
  std::unique_ptr<Fft> fft_;
};

}  // namespace uavsim::sensors
