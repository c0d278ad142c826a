#include "sensors/radar_processor.h"

#include <fftw3.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <string>

#include "core/interrupt.h"
#include "core/physical_constants.h"

namespace uavsim::sensors {
namespace {

using core::kDegToRad;
using core::kPi;
using core::kSpeedOfLight_mps;
// The pattern search stops refining a MUSIC peak below this step.
constexpr double kMusicTolDeg = 5e-3;
// Floor of the CFAR noise estimate, in units of the thermal noise of a cell.
// With thermal noise the estimate never comes near it (its spread is a few
// per cent); a noise-free cube would otherwise detect every rounding error.
constexpr double kMinCfarNoise = 0.1;

// FFTW's planner and plan destruction are not thread-safe; this file is the
// only FFTW user in the library, so one lock here makes construction and
// destruction of processors on several threads safe.
std::mutex& FftwPlannerMutex() {
  static std::mutex m;
  return m;
}

fftwf_complex* AsFftw(std::complex<float>* p) { return reinterpret_cast<fftwf_complex*>(p); }

int Wrap(int i, int n) {
  i %= n;
  return i < 0 ? i + n : i;
}

// Parabola through (-1, l), (0, c), (1, r): the vertex offset, within half a
// bin; 0 when the three points do not make a peak.
double ParabolicOffset(double l, double c, double r) {
  const double denom = l - 2.0 * c + r;
  if (!(denom < 0.0)) return 0.0;
  return std::clamp(0.5 * (l - r) / denom, -0.5, 0.5);
}

// |rho(k)|^2 = |sum_n w[n]^2 exp(-j 2 pi k n / N)|^2 / (sum w^2)^2: the
// correlation of the noise powers of two DFT bins k apart.
std::vector<double> BinPowerCorrelation(const std::vector<double>& w, int max_lag) {
  double sum_w2 = 0.0;
  for (double x : w) sum_w2 += x * x;
  const int n = static_cast<int>(w.size());
  std::vector<double> out(max_lag + 1, 0.0);
  for (int k = 0; k <= max_lag; ++k) {
    std::complex<double> acc = 0.0;
    for (int i = 0; i < n; ++i)
      acc += w[i] * w[i] * std::polar(1.0, -2.0 * kPi * static_cast<double>(k) * i / n);
    out[k] = std::norm(acc) / (sum_w2 * sum_w2);
  }
  return out;
}

// S(X, Y) = sum_{x in X, y in Y} |rho(x - y)|^2: the correlation of the
// noise powers of two sets of cells along one axis (CFAR training variance).
double PairSum(const std::vector<int>& x, const std::vector<int>& y,
               const std::vector<double>& rho) {
  double acc = 0.0;
  for (int a : x)
    for (int b : y) acc += rho[std::abs(a - b)];
  return acc;
}

// Degrees of freedom of the snapshots' sample covariance: the cells of a
// neighbourhood share noise through the windows, so K of them are worth
// K^2 / sum_ij |C_ij|^2 independent ones (C their correlation; 3.5 of the
// 9 cells of a 3 x 3 Hann neighbourhood). Forward-backward averaging adds
// none for this purpose (MDL on an FB covariance over-counts, Xu, Roy &
// Kailath, IEEE TSP 42(1), 1994). MDL needs it: with the nominal K it
// finds phantom sources.
double SnapshotDegreesOfFreedom(const std::vector<double>& wr, const std::vector<double>& wd,
                                int h) {
  const std::vector<double> cr = BinPowerCorrelation(wr, 2 * h);
  const std::vector<double> cd = BinPowerCorrelation(wd, 2 * h);
  double sr = 0.0, sd = 0.0;
  for (int i = -h; i <= h; ++i)
    for (int j = -h; j <= h; ++j) sr += cr[std::abs(i - j)], sd += cd[std::abs(i - j)];
  const double k = (2.0 * h + 1.0) * (2.0 * h + 1.0);
  return k * k / (sr * sd);
}

}  // namespace

struct RadarProcessor::Fft {
  fftwf_plan range = nullptr;     // Ns-point, over all chirps and antennas
  fftwf_plan doppler = nullptr;   // Nc-point, stride Ns, over range bins and antennas
  fftwf_plan beamscan = nullptr;  // 2-D, in place
  int beam_x = 1, beam_y = 1;     // beamscan grid (x fastest)

  ~Fft() {
    std::lock_guard<std::mutex> lock(FftwPlannerMutex());
    for (fftwf_plan p : {range, doppler, beamscan})
      if (p) fftwf_destroy_plan(p);
  }
};

std::vector<double> RadarProcessor::Window(RadarWindow type, int n) {
  std::vector<double> w(n, 1.0);
  if (n <= 1) return w;
  double a0 = 1.0, a1 = 0.0, a2 = 0.0;
  switch (type) {
    case RadarWindow::kHann:
      a0 = 0.5, a1 = 0.5;
      break;
    case RadarWindow::kHamming:
      a0 = 0.54, a1 = 0.46;
      break;
    case RadarWindow::kBlackman:
      a0 = 0.42, a1 = 0.5, a2 = 0.08;
      break;
    case RadarWindow::kRectangular:
      break;
  }
  for (int i = 0; i < n; ++i) {
    const double x = 2.0 * kPi * i / n;
    w[i] = a0 - a1 * std::cos(x) + a2 * std::cos(2.0 * x);
  }
  return w;
}

double RadarProcessor::CaCfarPfa(double alpha, int training_cells, double shape, double scale,
                                 int integrated) {
  // E_S[P(Gamma(M, 1) > beta S)] with S ~ Gamma(shape, scale): the Poisson
  // sum of the Gamma(M) tail integrated against the Gamma density of S.
  const double bt = alpha / training_cells * scale;
  const double log1p_bt = std::log1p(bt);
  const double lg_shape = std::lgamma(shape);
  double pfa = 0.0;
  for (int k = 0; k < integrated; ++k) {
    const double log_term = std::lgamma(shape + k) - lg_shape - std::lgamma(k + 1.0) +
                            (k > 0 ? k * std::log(bt) : 0.0) - (shape + k) * log1p_bt;
    pfa += std::exp(log_term);
  }
  return pfa;
}

double RadarProcessor::CaCfarThresholdFactor(double pfa, int training_cells, double shape,
                                             double scale, int integrated) {
  double lo = 0.0, hi = 1.0;
  while (CaCfarPfa(hi, training_cells, shape, scale, integrated) > pfa && hi < 1e300) hi *= 2.0;
  // Bisection to double precision: Pfa falls monotonically in alpha.
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (CaCfarPfa(mid, training_cells, shape, scale, integrated) > pfa ? lo : hi) = mid;
  }
  return hi;
}

RadarProcessor::RadarProcessor(const FmcwRadarConfig& config)
    : config_(config), fft_(std::make_unique<Fft>()) {
  CheckShape();
  DeriveBinSizes();
  const RadarProcessingConfig& p = config_.processing;
  const std::vector<double> wr = Window(p.range_window, samples_);
  const std::vector<double> wd = Window(p.doppler_window, chirps_);
  MakeWindows(wr, wd);
  const std::vector<bool> has_noise = MakeNoiseScale(wr, wd);
  MakeCfarRows(wr, wd, has_noise);
  snapshot_dof_ = SnapshotDegreesOfFreedom(wr, wd, p.snapshot_neighbourhood_cells);
  MakeMusicGrid();
  PlanFfts();
}

void RadarProcessor::CheckShape() {
  const RadarProcessingConfig& p = config_.processing;
  samples_ = config_.adc_samples;
  chirps_ = config_.chirps_per_frame;
  nx_ = config_.nx;
  ny_ = config_.ny;
  antennas_ = nx_ * ny_;
  if (samples_ < 1 || chirps_ < 1 || nx_ < 1 || ny_ < 1)
    throw std::invalid_argument(
        "RadarProcessor: adc_samples, chirps_per_frame, nx and ny must be positive");
  cfar_half_range_ = p.cfar_guard_range_cells + p.cfar_training_range_cells;
  cfar_half_doppler_ = p.cfar_guard_doppler_cells + p.cfar_training_doppler_cells;
  if (2 * cfar_half_range_ + 1 > samples_)
    throw std::invalid_argument(
        "processing/cfar_training_range_cells: the CFAR window (2 * (guard + training) + 1 = " +
        std::to_string(2 * cfar_half_range_ + 1) + " range cells) exceeds adc_samples (" +
        std::to_string(samples_) + ")");
  if (2 * cfar_half_doppler_ + 1 > chirps_)
    throw std::invalid_argument(
        "processing/cfar_training_doppler_cells: the CFAR window (2 * (guard + training) + 1 = " +
        std::to_string(2 * cfar_half_doppler_ + 1) + " Doppler cells) exceeds chirps_per_frame (" +
        std::to_string(chirps_) + ")");
  if (p.source_count == SourceCount::kMdl && p.max_sources >= antennas_)
    throw std::invalid_argument("processing/max_sources: " + std::to_string(p.max_sources) +
                                " sources need more than the array's " + std::to_string(antennas_) +
                                " elements");
}

void RadarProcessor::DeriveBinSizes() {
  lambda_m_ = kSpeedOfLight_mps / (config_.carrier_ghz * 1e9);
  dx_m_ = config_.spacing_x_wavelengths * lambda_m_;
  dy_m_ = config_.spacing_y_wavelengths * lambda_m_;
  const double slope_hz_per_s = config_.bandwidth_mhz * 1e6 / (config_.chirp_duration_us * 1e-6);
  const double fs_hz = config_.sample_rate_msps * 1e6;
  // Step 1: range_bin_m = c fs / (2 K Ns).
  range_bin_m_ = kSpeedOfLight_mps * fs_hz / (2.0 * slope_hz_per_s * samples_);
  const double chirp_period_s = (config_.chirp_duration_us + config_.idle_time_us) * 1e-6;
  // Step 3: velocity_bin_mps = lambda / (2 Nc T_c).
  velocity_bin_mps_ = lambda_m_ / (2.0 * chirps_ * chirp_period_s);
}

void RadarProcessor::MakeWindows(const std::vector<double>& wr, const std::vector<double>& wd) {
  // The Doppler weights also carry exp(j 2 pi c h / Nc), h = floor(Nc / 2),
  // which shifts the spectrum by h bins: the FFT's output is then already
  // fftshifted, at no extra pass.
  range_window_.assign(wr.begin(), wr.end());
  doppler_weights_.resize(chirps_);
  mean_weights_.resize(chirps_);
  const int shift = chirps_ / 2;
  const double sum_wd = std::accumulate(wd.begin(), wd.end(), 0.0);
  for (int c = 0; c < chirps_; ++c) {
    doppler_weights_[c] = std::complex<float>(
        std::polar(wd[c], 2.0 * kPi * static_cast<double>(c) * shift / chirps_));
    mean_weights_[c] = static_cast<float>(wd[c] / sum_wd);
  }
}

std::vector<bool> RadarProcessor::MakeNoiseScale(const std::vector<double>& wr,
                                                 const std::vector<double>& wd) {
  // Noise power of each Doppler bin for unit white noise per sample. With
  // clutter removal bin d is sum_c (q_c - Q w_c / sum w) x_c, q_c its
  // weights and Q their sum: zero at zero Doppler, changed next to it (the
  // window's own DFT is non-zero there), untouched elsewhere. Dividing it
  // out keeps the CFAR's noise estimate right next to the notch.
  const RadarProcessingConfig& p = config_.processing;
  const int shift = chirps_ / 2;
  const double sum_wd = std::accumulate(wd.begin(), wd.end(), 0.0);
  double sum_wr2 = 0.0;
  for (double x : wr) sum_wr2 += x * x;
  double sum_wd2 = 0.0;
  for (double x : wd) sum_wd2 += x * x;
  power_scale_.assign(chirps_, 0.0f);
  std::vector<bool> has_noise(chirps_, false);
  for (int d = 0; d < chirps_; ++d) {
    std::vector<std::complex<double>> q(chirps_);
    std::complex<double> sum_q = 0.0;
    for (int c = 0; c < chirps_; ++c) {
      q[c] = std::polar(wd[c], -2.0 * kPi * static_cast<double>(d - shift) * c / chirps_);
      sum_q += q[c];
    }
    double var = 0.0;
    for (int c = 0; c < chirps_; ++c)
      var += std::norm(p.clutter_removal ? q[c] - sum_q * (wd[c] / sum_wd) : q[c]);
    // The zero-Doppler bin holds nothing after clutter removal: it stays 0
    // and is neither tested nor used for training.
    has_noise[d] = var > 1e-9 * sum_wd2;
    // Step 4: 1 / (M sum(w_r^2) sum|q - Q w / sum w|^2).
    if (has_noise[d]) power_scale_[d] = static_cast<float>(1.0 / (antennas_ * sum_wr2 * var));
  }
  return has_noise;
}

void RadarProcessor::MakeCfarRows(const std::vector<double>& wr, const std::vector<double>& wd,
                                  const std::vector<bool>& has_noise) {
  // The training cells of Doppler bin d are the window rectangle minus the
  // guard rectangle, without rows that hold no noise. Cov(P_i, P_j) of two
  // noise-only cells is M |rho_r|^2 |rho_d|^2 (complex Gaussian fourth
  // moments; one antenna's cell has unit mean), and both rectangles are
  // products of a range and a Doppler interval, so the variance of the
  // training sum separates:
  //   sum_{T x T} = S_r(B, B) S_d(B, B) - 2 S_r(B, G) S_d(B, G) + S_r(G, G) S_d(G, G)
  // with S(X, Y) = sum_{x in X, y in Y} |rho(x - y)|^2, B the window and G
  // the guard intervals.
  const RadarProcessingConfig& p = config_.processing;
  const std::vector<double> rho_r = BinPowerCorrelation(wr, 2 * cfar_half_range_);
  const std::vector<double> rho_d = BinPowerCorrelation(wd, 2 * cfar_half_doppler_);
  std::vector<int> range_window, range_guard;
  for (int dr = -cfar_half_range_; dr <= cfar_half_range_; ++dr) {
    range_window.push_back(dr);
    if (std::abs(dr) <= p.cfar_guard_range_cells) range_guard.push_back(dr);
  }
  const double sr_bb = PairSum(range_window, range_window, rho_r);
  const double sr_bg = PairSum(range_window, range_guard, rho_r);
  const double sr_gg = PairSum(range_guard, range_guard, rho_r);
  std::map<std::vector<bool>, CfarRow> by_pattern;  // few distinct: away from zero Doppler, one
  cfar_rows_.resize(chirps_);
  for (int d = 0; d < chirps_; ++d) {
    if (!has_noise[d]) continue;
    std::vector<bool> pattern;
    std::vector<int> doppler_window, doppler_guard;
    for (int dd = -cfar_half_doppler_; dd <= cfar_half_doppler_; ++dd) {
      pattern.push_back(has_noise[Wrap(d + dd, chirps_)]);
      if (!pattern.back()) continue;
      doppler_window.push_back(dd);
      if (std::abs(dd) <= p.cfar_guard_doppler_cells) doppler_guard.push_back(dd);
    }
    auto it = by_pattern.find(pattern);
    if (it == by_pattern.end()) {
      CfarRow row;
      row.training_cells = static_cast<int>(range_window.size() * doppler_window.size() -
                                            range_guard.size() * doppler_guard.size());
      if (row.training_cells > 0) {
        const double sum_rho = sr_bb * PairSum(doppler_window, doppler_window, rho_d) -
                               2.0 * sr_bg * PairSum(doppler_window, doppler_guard, rho_d) +
                               sr_gg * PairSum(doppler_guard, doppler_guard, rho_d);
        // Step 5: the Gamma moment match, shape N^2 M / sum and scale sum / N.
        const double n = row.training_cells;
        row.shape = n * n * antennas_ / sum_rho;
        row.scale = sum_rho / n;
        row.alpha =
            CaCfarThresholdFactor(p.cfar_pfa, row.training_cells, row.shape, row.scale, antennas_);
        row.tested = true;
      }
      it = by_pattern.emplace(pattern, row).first;
    }
    cfar_rows_[d] = it->second;
  }
  // The accessors report the rows far from zero Doppler (all rows used).
  for (int d = 0; d < chirps_; ++d)
    if (cfar_rows_[d].tested && cfar_rows_[d].training_cells > cfar_full_.training_cells)
      cfar_full_ = cfar_rows_[d];
}

void RadarProcessor::MakeMusicGrid() {
  // MUSIC's coarse grid over the field of view, front hemisphere only (the
  // planar array cannot tell front from back); an axis with one element
  // carries no information and is pinned at 0.
  const RadarProcessingConfig& p = config_.processing;
  const auto axis = [&](double fov_deg, int elements) {
    std::vector<double> v;
    if (elements < 2) return std::vector<double>{0.0};
    const double half = std::min(0.5 * fov_deg, 90.0);
    const int n_half = static_cast<int>(std::floor(half / p.music_grid_step_deg + 1e-9));
    for (int i = -n_half; i <= n_half; ++i) v.push_back(i * p.music_grid_step_deg * kDegToRad);
    return v;
  };
  const std::vector<double> az = axis(config_.fov_azimuth_deg, nx_);
  const std::vector<double> el = axis(config_.fov_elevation_deg, ny_);
  grid_az_ = static_cast<int>(az.size());
  grid_el_ = static_cast<int>(el.size());
  grid_steering_.resize(grid_az_ * grid_el_, antennas_);
  for (int ie = 0; ie < grid_el_; ++ie)
    for (int ia = 0; ia < grid_az_; ++ia) {
      grid_.push_back({az[ia], el[ie]});
      grid_steering_.row(ie * grid_az_ + ia) = Steering(grid_.back()).adjoint();
    }
}

void RadarProcessor::PlanFfts() {
  // FFTW_ESTIMATE: the plan, hence every rounding, does not depend on
  // timing, so a seed gives the same frames bit for bit. All buffers are
  // 64-byte aligned, as these planning arrays are, so the plans may run on
  // them (new-array execution, thread-safe).
  const int beam_n = config_.processing.beamscan_fft_size;
  fft_->beam_x = nx_ > 1 ? std::max(beam_n, nx_) : 1;
  fft_->beam_y = ny_ > 1 ? std::max(beam_n, ny_) : 1;
  {
    std::lock_guard<std::mutex> lock(FftwPlannerMutex());
    FftBuffer cube(static_cast<std::size_t>(samples_) * chirps_ * antennas_);
    fft_->range = fftwf_plan_many_dft(1, &samples_, chirps_ * antennas_, AsFftw(cube.data()),
                                      nullptr, 1, samples_, AsFftw(cube.data()), nullptr, 1,
                                      samples_, FFTW_FORWARD, FFTW_ESTIMATE);
    fftwf_iodim dim{chirps_, samples_, samples_};
    fftwf_iodim loops[2] = {{antennas_, chirps_ * samples_, chirps_ * samples_}, {samples_, 1, 1}};
    fft_->doppler = fftwf_plan_guru_dft(1, &dim, 2, loops, AsFftw(cube.data()), AsFftw(cube.data()),
                                        FFTW_FORWARD, FFTW_ESTIMATE);
    FftBuffer beam(static_cast<std::size_t>(fft_->beam_x) * fft_->beam_y);
    fft_->beamscan = fftwf_plan_dft_2d(fft_->beam_y, fft_->beam_x, AsFftw(beam.data()),
                                       AsFftw(beam.data()), FFTW_FORWARD, FFTW_ESTIMATE);
  }
  if (!fft_->range || !fft_->doppler || !fft_->beamscan)
    throw std::runtime_error("RadarProcessor: FFTW could not plan the transforms");
}

RadarProcessor::~RadarProcessor() = default;

void RadarProcessor::CheckCube(const RadarCube& cube) const {
  if (cube.samples != samples_ || cube.chirps != chirps_ || cube.nx != nx_ || cube.ny != ny_ ||
      cube.data.size() != static_cast<std::size_t>(samples_) * chirps_ * antennas_)
    throw std::invalid_argument(
        "RadarProcessor: cube of " + std::to_string(cube.samples) + " samples x " +
        std::to_string(cube.chirps) + " chirps x " + std::to_string(cube.nx) + " x " +
        std::to_string(cube.ny) + " antennas (" + std::to_string(cube.data.size()) +
        " values) does not match the config's " + std::to_string(samples_) + " x " +
        std::to_string(chirps_) + " x " + std::to_string(nx_) + " x " + std::to_string(ny_));
}

Eigen::VectorXcd RadarProcessor::Steering(const AngleOfArrival& d) const {
  const double u_y = std::cos(d.elevation_rad) * std::sin(d.azimuth_rad);
  const double u_z = std::sin(d.elevation_rad);
  // Products of two unit phasors rather than M complex exponentials.
  const std::complex<double> step_x = std::polar(1.0, 2.0 * kPi * dx_m_ * u_y / lambda_m_);
  const std::complex<double> step_y = std::polar(1.0, 2.0 * kPi * dy_m_ * u_z / lambda_m_);
  Eigen::VectorXcd a(antennas_);
  std::complex<double> row = 1.0;
  for (int iy = 0; iy < ny_; ++iy, row *= step_y) {
    std::complex<double> v = row;
    for (int ix = 0; ix < nx_; ++ix, v *= step_x) a(iy * nx_ + ix) = v;
  }
  return a;
}

AngleOfArrival RadarProcessor::FromDirectionCosines(double u_y, double u_z) const {
  const double s = std::hypot(u_y, u_z);
  if (s > 1.0) u_y /= s, u_z /= s;
  const double u_x = std::sqrt(std::max(0.0, 1.0 - u_y * u_y - u_z * u_z));
  return {std::atan2(u_y, u_x), std::asin(std::clamp(u_z, -1.0, 1.0))};
}

RadarCube RadarProcessor::RangeProfiles(const RadarCube& cube) const {
  CheckCube(cube);
  FftBuffer work(cube.data.size());
  for (std::size_t row = 0; row < cube.data.size(); row += samples_)
    for (int s = 0; s < samples_; ++s) work[row + s] = cube.data[row + s] * range_window_[s];
  fftwf_execute_dft(fft_->range, AsFftw(work.data()), AsFftw(work.data()));
  RadarCube out = cube;
  std::copy(work.begin(), work.end(), out.data.begin());
  return out;
}

void RadarProcessor::TransformInto(const RadarCube& cube, RangeDopplerCube& rd) const {
  rd.range_bins = samples_;
  rd.doppler_bins = chirps_;
  rd.antennas = antennas_;
  FftBuffer& x = rd.spectra;
  x.resize(cube.data.size());
  const std::size_t plane = static_cast<std::size_t>(chirps_) * samples_;

  // 1. Range FFT of the windowed samples, all rows at once.
  for (std::size_t row = 0; row < x.size(); row += samples_)
    for (int s = 0; s < samples_; ++s) x[row + s] = cube.data[row + s] * range_window_[s];
  fftwf_execute_dft(fft_->range, AsFftw(x.data()), AsFftw(x.data()));

  // 2-3. Clutter removal and the Doppler weights, row by row (chirps are
  // rows of Ns range bins): contiguous passes instead of strided ones.
  std::vector<std::complex<float>> mean(samples_);
  for (int a = 0; a < antennas_; ++a) {
    std::complex<float>* base = x.data() + a * plane;
    if (config_.processing.clutter_removal) {
      // The mean weighted by the Doppler window: it removes a constant
      // exactly, as the plain mean does, but a moving target leaks into it
      // only through the window's sidelobes. The plain mean of an off-bin
      // mover is sin(pi f) / (pi f) of its amplitude, -30 dB at 10 bins,
      // and its subtraction paints a false target at zero Doppler.
      std::fill(mean.begin(), mean.end(), std::complex<float>(0.0f, 0.0f));
      for (int c = 0; c < chirps_; ++c) {
        const float w = mean_weights_[c];
        for (int r = 0; r < samples_; ++r) mean[r] += w * base[c * samples_ + r];
      }
      for (int c = 0; c < chirps_; ++c)
        for (int r = 0; r < samples_; ++r) base[c * samples_ + r] -= mean[r];
    }
    for (int c = 0; c < chirps_; ++c) {
      const std::complex<float> w = doppler_weights_[c];
      for (int r = 0; r < samples_; ++r) base[c * samples_ + r] *= w;
    }
  }
  fftwf_execute_dft(fft_->doppler, AsFftw(x.data()), AsFftw(x.data()));

  // 4. Non-coherent sum over antennas.
  rd.power.assign(plane, 0.0f);
  for (int a = 0; a < antennas_; ++a) {
    const std::complex<float>* base = x.data() + a * plane;
    for (std::size_t i = 0; i < plane; ++i) rd.power[i] += std::norm(base[i]);
  }
  for (int d = 0; d < chirps_; ++d) {
    float* row = rd.power.data() + static_cast<std::size_t>(d) * samples_;
    for (int r = 0; r < samples_; ++r) row[r] *= power_scale_[d];
  }
}

RangeDopplerCube RadarProcessor::Transform(const RadarCube& cube) const {
  CheckCube(cube);
  RangeDopplerCube rd;
  TransformInto(cube, rd);
  return rd;
}

CfarResult RadarProcessor::Cfar(const std::vector<float>& power) const {
  const std::size_t cells = static_cast<std::size_t>(samples_) * chirps_;
  if (power.size() != cells)
    throw std::invalid_argument("RadarProcessor::Cfar: map of " + std::to_string(power.size()) +
                                " cells, expected " + std::to_string(cells));
  const RadarProcessingConfig& p = config_.processing;
  CfarResult out;
  out.detected.assign(cells, 0);
  out.noise.assign(cells, 0.0f);

  // Summed-area table over the map padded circularly in Doppler, in double
  // (differences of large sums): every window sum costs four look-ups.
  const int hd = cfar_half_doppler_, hr = cfar_half_range_;
  const int rows = chirps_ + 2 * hd, cols = samples_;
  std::vector<double> sat(static_cast<std::size_t>(rows + 1) * (cols + 1), 0.0);
  const auto at = [&](int i, int j) -> double& {
    return sat[static_cast<std::size_t>(i) * (cols + 1) + j];
  };
  for (int i = 0; i < rows; ++i) {
    const float* src = power.data() + static_cast<std::size_t>(Wrap(i - hd, chirps_)) * samples_;
    double run = 0.0;
    for (int j = 0; j < cols; ++j) {
      run += src[j];
      at(i + 1, j + 1) = at(i, j + 1) + run;
    }
  }
  // Sum over padded rows [i0, i1] and columns [j0, j1].
  const auto box = [&](int i0, int i1, int j0, int j1) {
    return at(i1 + 1, j1 + 1) - at(i0, j1 + 1) - at(i1 + 1, j0) + at(i0, j0);
  };
  const int gr = p.cfar_guard_range_cells, gd = p.cfar_guard_doppler_cells;
  for (int d = 0; d < chirps_; ++d) {
    const CfarRow& row = cfar_rows_[d];
    if (!row.tested) continue;
    // Rows without noise are zero in the map, so the box sums skip them.
    const double n = row.training_cells;
    const int i = d + hd;  // padded row of Doppler bin d
    for (int r = hr; r < samples_ - hr; ++r) {
      const double sum = box(i - hd, i + hd, r - hr, r + hr) - box(i - gd, i + gd, r - gr, r + gr);
      const double noise = std::max(sum / n, kMinCfarNoise);
      const std::size_t k = static_cast<std::size_t>(d) * samples_ + r;
      out.noise[k] = static_cast<float>(noise);
      out.detected[k] = power[k] > row.alpha * noise;
      ++out.cells_tested;
    }
  }
  return out;
}

std::vector<RadarDetection> RadarProcessor::Detect(const RangeDopplerCube& rd) const {
  const CfarResult cfar = Cfar(rd.power);
  const auto P = [&](int r, int d) {
    return rd.power[static_cast<std::size_t>(Wrap(d, chirps_)) * samples_ + r];
  };
  std::vector<RadarDetection> out;
  for (int d = 0; d < chirps_; ++d)
    for (int r = 0; r < samples_; ++r) {
      const std::size_t k = static_cast<std::size_t>(d) * samples_ + r;
      if (!cfar.detected[k]) continue;
      // A local maximum of its 3 x 3 neighbourhood; on a tie the cell that
      // comes first in the map wins, so a flat top gives one detection.
      const float v = rd.power[k];
      bool peak = true;
      for (int dd = -1; dd <= 1 && peak; ++dd)
        for (int dr = -1; dr <= 1 && peak; ++dr) {
          if (dr == 0 && dd == 0) continue;
          const int rr = r + dr;
          if (rr < 0 || rr >= samples_) continue;
          const float u = P(rr, d + dd);
          const bool before = dd < 0 || (dd == 0 && dr < 0);
          peak = before ? v > u : v >= u;
        }
      if (!peak) continue;
      RadarDetection det;
      det.range_bin = r;
      det.doppler_bin = d;
      det.power = v;
      det.noise = cfar.noise[k];
      det.snr_db = 10.0 * std::log10(det.power / det.noise);
      double r_hat = r, d_hat = d;
      if (config_.processing.interpolate_peaks) {
        // Tested cells are at least a CFAR half-window from the range ends.
        // Next to the empty zero-Doppler bin there is no parabola to fit.
        const auto offset = [](double l, double c, double r) {
          return l > 0.0 && r > 0.0 ? ParabolicOffset(std::log(l), std::log(c), std::log(r)) : 0.0;
        };
        r_hat += offset(P(r - 1, d), v, P(r + 1, d));
        d_hat += offset(P(r, d - 1), v, P(r, d + 1));
      }
      det.range_m = r_hat * range_bin_m_;
      det.radial_velocity_mps = (d_hat - chirps_ / 2) * velocity_bin_mps_;
      out.push_back(det);
    }
  // Strongest first; ties in map order, so the result does not depend on
  // the sort's implementation.
  std::stable_sort(out.begin(), out.end(), [](const RadarDetection& a, const RadarDetection& b) {
    return a.power > b.power;
  });
  if (out.size() > static_cast<std::size_t>(config_.processing.max_detections))
    out.resize(config_.processing.max_detections);
  return out;
}

Eigen::MatrixXcd RadarProcessor::Snapshots(const RangeDopplerCube& rd,
                                           const RadarDetection& det) const {
  const int h = config_.processing.snapshot_neighbourhood_cells;
  std::vector<std::pair<int, int>> cells = {{det.range_bin, det.doppler_bin}};
  for (int dd = -h; dd <= h; ++dd)
    for (int dr = -h; dr <= h; ++dr) {
      const int r = det.range_bin + dr;
      // A short frame would wrap a Doppler neighbour onto the cell itself.
      if ((dr == 0 && dd == 0) || r < 0 || r >= rd.range_bins || std::abs(dd) >= rd.doppler_bins)
        continue;
      cells.emplace_back(r, Wrap(det.doppler_bin + dd, rd.doppler_bins));
    }
  Eigen::MatrixXcd x(antennas_, static_cast<int>(cells.size()));
  for (int k = 0; k < x.cols(); ++k)
    for (int a = 0; a < antennas_; ++a) {
      const std::complex<float> v = rd.at(cells[k].first, cells[k].second, a);
      x(a, k) = std::complex<double>(v.real(), v.imag());
    }
  return x;
}

Eigen::MatrixXcd RadarProcessor::Covariance(const Eigen::MatrixXcd& snapshots) const {
  Eigen::MatrixXcd r = snapshots * snapshots.adjoint() / static_cast<double>(snapshots.cols());
  if (config_.processing.forward_backward) {
    // J conj(R) J with J the exchange matrix: element m <-> M - 1 - m is
    // (ix, iy) <-> (nx - 1 - ix, ny - 1 - iy), the array's centre symmetry.
    const Eigen::MatrixXcd flipped = r.conjugate().reverse();
    r = 0.5 * (r + flipped);
  }
  return r;
}

int RadarProcessor::SourceCountOf(const Eigen::MatrixXcd& snapshots) const {
  const RadarProcessingConfig& p = config_.processing;
  if (p.source_count == SourceCount::kOne || antennas_ < 2) return 1;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> eig(Covariance(snapshots),
                                                            Eigen::EigenvaluesOnly);
  if (eig.info() != Eigen::Success) return 1;
  const Eigen::VectorXd& lambda = eig.eigenvalues();  // ascending
  const int m = antennas_;
  // Snapshots as Snapshots() builds them carry snapshot_dof_ degrees of
  // freedom; others are taken as independent.
  const int full =
      (2 * p.snapshot_neighbourhood_cells + 1) * (2 * p.snapshot_neighbourhood_cells + 1);
  const double k_snap = snapshots.cols() == full ? snapshot_dof_ : snapshots.cols();
  // MDL (Wax & Kailath 1985): the likelihood that the m - k smallest
  // eigenvalues are equal (noise), plus half the free parameters' log K.
  int best = 0;
  double best_mdl = std::numeric_limits<double>::infinity();
  for (int k = 0; k < m; ++k) {
    const int q = m - k;
    double log_geo = 0.0, arith = 0.0;
    for (int i = 0; i < q; ++i) {
      const double l = std::max(lambda(i), 1e-300);
      log_geo += std::log(l);
      arith += l;
    }
    log_geo /= q;
    arith /= q;
    const double mdl =
        -k_snap * q * (log_geo - std::log(arith)) + 0.5 * k * (2.0 * m - k) * std::log(k_snap);
    if (mdl < best_mdl) best_mdl = mdl, best = k;
  }
  return std::clamp(best, 1, std::min(p.max_sources, m - 1));
}

double RadarProcessor::MusicSpectrum(const Eigen::MatrixXcd& es, double az_rad,
                                     double el_rad) const {
  return (Steering({az_rad, el_rad}).adjoint() * es).squaredNorm();
}

std::vector<AngleOfArrival> RadarProcessor::Music(const Eigen::MatrixXcd& snapshots,
                                                  int sources) const {
  if (antennas_ < 2 || snapshots.rows() != antennas_ || snapshots.cols() < 1) return {};
  sources = std::clamp(sources, 1, antennas_ - 1);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> eig(Covariance(snapshots));
  if (eig.info() != Eigen::Success || !eig.eigenvectors().allFinite()) return {};
  // Signal subspace: the eigenvectors of the largest eigenvalues. Maximising
  // ||E_s^H a||^2 is minimising ||E_n^H a||^2 = M - ||E_s^H a||^2.
  const Eigen::MatrixXcd es = eig.eigenvectors().rightCols(sources);
  const Eigen::VectorXd spectrum = (grid_steering_ * es).rowwise().squaredNorm();

  // Peaks of the coarse grid, strongest first.
  std::vector<int> peaks;
  for (int ie = 0; ie < grid_el_; ++ie)
    for (int ia = 0; ia < grid_az_; ++ia) {
      const double v = spectrum(ie * grid_az_ + ia);
      bool peak = true;
      for (int de = -1; de <= 1 && peak; ++de)
        for (int da = -1; da <= 1 && peak; ++da) {
          const int je = ie + de, ja = ia + da;
          if ((de == 0 && da == 0) || je < 0 || je >= grid_el_ || ja < 0 || ja >= grid_az_)
            continue;
          const double u = spectrum(je * grid_az_ + ja);
          peak = (de < 0 || (de == 0 && da < 0)) ? v > u : v >= u;
        }
      if (peak) peaks.push_back(ie * grid_az_ + ia);
    }
  std::stable_sort(peaks.begin(), peaks.end(),
                   [&](int a, int b) { return spectrum(a) > spectrum(b); });
  if (peaks.size() > static_cast<std::size_t>(sources)) peaks.resize(sources);

  // Pattern search from each grid peak: step to the best of the 8
  // neighbours, halve the step when none is better.
  const double max_rad = 0.5 * kPi;
  std::vector<AngleOfArrival> out;
  for (int g : peaks) {
    double az = grid_[g].azimuth_rad, el = grid_[g].elevation_rad;
    double best = spectrum(g);
    double h = 0.5 * config_.processing.music_grid_step_deg * kDegToRad;
    const int step_az = nx_ > 1 ? 1 : 0, step_el = ny_ > 1 ? 1 : 0;
    for (int it = 0; it < 400 && h > kMusicTolDeg * kDegToRad; ++it) {
      double best_az = az, best_el = el;
      for (int de = -step_el; de <= step_el; ++de)
        for (int da = -step_az; da <= step_az; ++da) {
          if (de == 0 && da == 0) continue;
          const double a = std::clamp(az + da * h, -max_rad, max_rad);
          const double e = std::clamp(el + de * h, -max_rad, max_rad);
          const double v = MusicSpectrum(es, a, e);
          if (v > best) best = v, best_az = a, best_el = e;
        }
      if (best_az == az && best_el == el) {
        h *= 0.5;
      } else {
        az = best_az, el = best_el;
      }
    }
    out.push_back({az, el});
  }
  return out;
}

std::vector<AngleOfArrival> RadarProcessor::Esprit(const Eigen::MatrixXcd& snapshots,
                                                   int sources) const {
  if (antennas_ < 2 || snapshots.rows() != antennas_ || snapshots.cols() < 1) return {};
  // Each shift needs more rows in its subarray than sources.
  int cap = antennas_ - 1;
  if (nx_ > 1) cap = std::min(cap, (nx_ - 1) * ny_);
  if (ny_ > 1) cap = std::min(cap, nx_ * (ny_ - 1));
  sources = std::clamp(sources, 1, cap);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> eig(Covariance(snapshots));
  if (eig.info() != Eigen::Success || !eig.eigenvectors().allFinite()) return {};
  const Eigen::MatrixXcd es = eig.eigenvectors().rightCols(sources);

  // Psi solving E1 Psi = E2 in least squares, E1 and E2 the rows of the
  // subarray and of its copy shifted by one element along an axis.
  const auto psi = [&](int shift_x, int shift_y) {
    const int sub_x = nx_ - shift_x, sub_y = ny_ - shift_y;
    Eigen::MatrixXcd e1(sub_x * sub_y, sources), e2(sub_x * sub_y, sources);
    for (int iy = 0; iy < sub_y; ++iy)
      for (int ix = 0; ix < sub_x; ++ix) {
        e1.row(iy * sub_x + ix) = es.row(iy * nx_ + ix);
        e2.row(iy * sub_x + ix) = es.row((iy + shift_y) * nx_ + ix + shift_x);
      }
    return Eigen::MatrixXcd(e1.completeOrthogonalDecomposition().solve(e2));
  };
  const Eigen::MatrixXcd zero = Eigen::MatrixXcd::Zero(sources, sources);
  const Eigen::MatrixXcd psi_x = nx_ > 1 ? psi(1, 0) : zero;
  const Eigen::MatrixXcd psi_y = ny_ > 1 ? psi(0, 1) : zero;
  if (!psi_x.allFinite() || !psi_y.allFinite()) return {};

  // Both are T^-1 diag(phases) T with the same T: the eigenvectors of a
  // generic combination diagonalise both and pair the x and y phases.
  Eigen::MatrixXcd tx = psi_x, ty = psi_y;
  if (sources > 1) {
    const Eigen::ComplexEigenSolver<Eigen::MatrixXcd> ces(psi_x + 0.61803398875 * psi_y);
    if (ces.info() != Eigen::Success) return {};
    const Eigen::MatrixXcd t = ces.eigenvectors();
    const Eigen::MatrixXcd t_inv = t.inverse();
    tx = t_inv * psi_x * t;
    ty = t_inv * psi_y * t;
  }
  std::vector<AngleOfArrival> out;
  for (int k = 0; k < sources; ++k) {
    const double u_y = nx_ > 1 ? std::arg(tx(k, k)) * lambda_m_ / (2.0 * kPi * dx_m_) : 0.0;
    const double u_z = ny_ > 1 ? std::arg(ty(k, k)) * lambda_m_ / (2.0 * kPi * dy_m_) : 0.0;
    // Noise can push the phases past the visible region; a little is kept
    // (projected onto it), more is a failed estimate.
    if (!std::isfinite(u_y) || !std::isfinite(u_z) || std::hypot(u_y, u_z) > 1.05) continue;
    out.push_back(FromDirectionCosines(u_y, u_z));
  }
  return out;
}

AngleOfArrival RadarProcessor::Beamscan(const Eigen::VectorXcd& snapshot) const {
  const int fx = fft_->beam_x, fy = fft_->beam_y;
  FftBuffer buf(static_cast<std::size_t>(fx) * fy, std::complex<float>(0.0f, 0.0f));
  for (int iy = 0; iy < ny_; ++iy)
    for (int ix = 0; ix < nx_; ++ix) {
      const std::complex<double> v = snapshot(iy * nx_ + ix);
      buf[static_cast<std::size_t>(iy) * fx + ix] = std::complex<float>(v.real(), v.imag());
    }
  fftwf_execute_dft(fft_->beamscan, AsFftw(buf.data()), AsFftw(buf.data()));
  // The forward DFT (kernel exp(-j...)) peaks at bin k = F dx u_y / lambda
  // (mod F) for a steering exp(+j 2 pi ix dx u_y / lambda).
  double best = -1.0, best_uy = 0.0, best_uz = 0.0;
  for (int ky = 0; ky < fy; ++ky) {
    const double f_y = static_cast<double>(ky >= (fy + 1) / 2 ? ky - fy : ky) / fy;
    const double u_z = ny_ > 1 ? f_y * lambda_m_ / dy_m_ : 0.0;
    for (int kx = 0; kx < fx; ++kx) {
      const double f_x = static_cast<double>(kx >= (fx + 1) / 2 ? kx - fx : kx) / fx;
      const double u_y = nx_ > 1 ? f_x * lambda_m_ / dx_m_ : 0.0;
      if (u_y * u_y + u_z * u_z > 1.0) continue;  // not a real direction
      const double v = std::norm(buf[static_cast<std::size_t>(ky) * fx + kx]);
      if (v > best) best = v, best_uy = u_y, best_uz = u_z;
    }
  }
  return FromDirectionCosines(best_uy, best_uz);
}

std::vector<AngleOfArrival> RadarProcessor::EstimateAngles(
    const Eigen::MatrixXcd& snapshots) const {
  std::vector<AngleOfArrival> out;
  switch (config_.processing.angle_method) {
    case AngleMethod::kMusic:
      out = Music(snapshots, SourceCountOf(snapshots));
      break;
    case AngleMethod::kEsprit:
      out = Esprit(snapshots, SourceCountOf(snapshots));
      break;
    case AngleMethod::kBeamscan:
      break;
  }
  if (out.empty()) out.push_back(Beamscan(snapshots.col(0)));
  return out;
}

RadarFrame RadarProcessor::Process(const RadarCube& cube, const Eigen::Isometry3d& X_WR,
                                   double t_capture_s) const {
  CheckCube(cube);
  RangeDopplerCube rd;
  TransformInto(cube, rd);
  const std::vector<RadarDetection> detections = Detect(rd);

  RadarFrame frame;
  frame.t_capture_s = t_capture_s;
  frame.cube_bytes = cube.RawBytes();
  for (const RadarDetection& det : detections) {
    core::ThrowIfInterrupted();  // angle estimation is O(antennas^3) per detection
    for (const AngleOfArrival& d : EstimateAngles(Snapshots(rd, det))) {
      const Eigen::Vector3d u(std::cos(d.elevation_rad) * std::cos(d.azimuth_rad),
                              std::cos(d.elevation_rad) * std::sin(d.azimuth_rad),
                              std::sin(d.elevation_rad));
      const Eigen::Vector3d p_W = X_WR * (det.range_m * u);
      frame.points.push_back(
          {static_cast<float>(p_W.x()), static_cast<float>(p_W.y()), static_cast<float>(p_W.z()),
           static_cast<float>(det.radial_velocity_mps), static_cast<float>(det.snr_db)});
    }
  }

  RangeDopplerMap& map = frame.range_doppler;
  map.range_bins = samples_;
  map.doppler_bins = chirps_;
  map.range_bin_m = range_bin_m_;
  map.velocity_bin_mps = velocity_bin_mps_;
  map.power_db.resize(rd.power.size());
  for (std::size_t i = 0; i < rd.power.size(); ++i)
    map.power_db[i] = 10.0f * std::log10(std::max(rd.power[i], 1e-30f));
  return frame;
}

}  // namespace uavsim::sensors
